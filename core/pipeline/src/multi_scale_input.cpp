// Widens a cloud's descriptors to the multi-scale model input (multi_scale_input.hpp).

#include "multi_scale_input.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/normals.hpp"
#include "primlabel/pipeline/labeling.hpp"

namespace primlabel::pipeline {

namespace {
// Surface variation (curvature as estimate_normals defines it) of every point at `radius`,
// scaled; 0 where it cannot be measured.
std::vector<float> scaled_variation(const PointCloud& cloud, float radius,
                                    const NeighborSearch& search, const RunContext& context) {
  PointCloud probe;
  probe.resize_unorganized(cloud.size());
  probe.xyz = cloud.xyz;
  probe.viewpoint = cloud.viewpoint;
  NormalOptions options;
  options.neighborhood = capped(Neighborhood::Radius(radius));
  estimate_normals(probe, options, context, &search);
  std::vector<float> out(cloud.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = std::isfinite(probe.curvature[i]) ? probe.curvature[i] * kSurfaceVariationScale : 0.f;
  return out;
}
}  // namespace

Descriptors multi_scale_input(const PointCloud& cloud, Descriptors descriptors,
                              const FeatureSettings& settings, const NeighborSearch& search,
                              const RunContext& context) {
  if (!settings.multi_scale()) return descriptors;
  const std::size_t n = cloud.size();
  const int d = settings.descriptor_dim();
  std::vector<Descriptors> blocks;
  blocks.push_back(std::move(descriptors));
  for (float radius : settings.extra_feature_radii) {
    FeatureOptions options;
    options.neighborhood = capped(Neighborhood::Radius(radius));
    options.fpfh_variant = settings.fpfh_variant;
    blocks.push_back(compute_fpfh(cloud, options, context, nullptr, &search, nullptr));
  }
  std::vector<std::vector<float>> variations;
  if (settings.surface_variation_features) {
    std::vector<float> radii = {settings.normals.radius, settings.features.radius};
    radii.insert(radii.end(), settings.extra_feature_radii.begin(),
                 settings.extra_feature_radii.end());
    for (float radius : radii)
      variations.push_back(scaled_variation(cloud, radius, search, context));
  }

  const int dim = settings.model_input_dim();
  Descriptors out = Descriptors::filled(n, dim, std::numeric_limits<float>::quiet_NaN());
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(blocks[0].row(i)[0])) continue;  // no descriptor: stays invalid
    std::span<float> row = out.row(i);
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      const std::span<const float> part = blocks[b].row(i);
      std::copy(part.begin(), part.end(), row.begin() + std::ptrdiff_t(b) * d);
    }
    const std::size_t tail = blocks.size() * std::size_t(d);
    for (std::size_t v = 0; v < variations.size(); ++v) row[tail + v] = variations[v][i];
    // An extra scale can be NaN where the first is not only through a NaN normal, which the
    // first would share; zero keeps the row usable all the same.
    for (float& value : row)
      if (!std::isfinite(value)) value = 0.0f;
  }
  return out;
}

Descriptors leading_values(Descriptors descriptors, int dim) {
  if (descriptors.dim <= dim || descriptors.empty()) {
    if (descriptors.dim > dim) descriptors.dim = dim;
    return descriptors;
  }
  const std::size_t n = descriptors.size();
  Descriptors out(dim, std::vector<float>(n * std::size_t(dim)));
  for (std::size_t i = 0; i < n; ++i) {
    const std::span<const float> row = descriptors.row(i);
    std::copy(row.begin(), row.begin() + dim, out.row(i).begin());
  }
  return out;
}

}  // namespace primlabel::pipeline
