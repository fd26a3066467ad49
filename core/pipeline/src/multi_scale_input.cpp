// Widens a cloud's descriptors to the multi-scale model input (multi_scale_input.hpp).

#include "multi_scale_input.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/neighbor_lists.hpp"
#include "primlabel/geometry/parallel.hpp"
#include "primlabel/geometry/point_moments.hpp"
#include "primlabel/pipeline/labeling.hpp"

namespace primlabel::pipeline {

namespace {
// The shared lists' budget: a 5 mm voxel frame holds ~200 neighbours a point within 40 mm.
constexpr std::size_t kListBytes = std::size_t(256) << 20;
constexpr std::size_t kBlock = 512;  // points per parallel block

// Surface variation of every point at each of `radii` (ascending), scaled, from one neighbour
// list a point at the largest: each smaller neighbourhood is the part of it within its radius
// (the same set a search at that radius finds, the nearest 1024 when capped). The covariance is
// that of estimate_normals (PointMoments); 0 where it is undefined.
std::vector<std::vector<float>> scaled_variations(const std::vector<Vec3f>& xyz,
                                                  const std::vector<float>& radii,
                                                  const NeighborLists& lists,
                                                  std::span<const std::uint8_t> wanted,
                                                  const RunContext& context) {
  const std::size_t n = xyz.size(), scales = radii.size();
  std::vector<std::vector<float>> out(scales, std::vector<float>(n, 0.0f));
  if (scales == 0) return out;
  const Neighborhood widest = capped(Neighborhood::Radius(radii.back()));
  const std::ptrdiff_t blocks = std::ptrdiff_t((n + kBlock - 1) / kBlock);
  detail::for_each_block(
      blocks, context, [] { return NeighborList{}; },
      [&](NeighborList& list, std::ptrdiff_t block) {
        std::vector<PointMoments> moments(scales);
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        for (std::size_t i = first; i < last; ++i) {
          if (!is_finite(xyz[i]) || (!wanted.empty() && !wanted[i])) continue;
          lists.find(i, widest, list);
          std::fill(moments.begin(), moments.end(), PointMoments{});
          for (std::size_t j = 0; j < list.size(); ++j) {
            // The terms PointMoments::add sums, computed once for every radius the neighbour is
            // within: the same values added in the same order, so the same bits.
            const Vec3f& p = xyz[list.indices[j]];
            const double x = double(p.x()) - xyz[i].x(), y = double(p.y()) - xyz[i].y(),
                         z = double(p.z()) - xyz[i].z();
            const double xx = x * x, xy = x * y, xz = x * z, yy = y * y, yz = y * z, zz = z * z;
            for (std::size_t r = scales; r-- > 0;) {
              if (list.sq_dists[j] > radii[r] * radii[r]) break;  // nor within any smaller radius
              PointMoments& m = moments[r];
              m.count += 1;
              m.sx += x, m.sy += y, m.sz += z;
              m.sxx += xx, m.sxy += xy, m.sxz += xz, m.syy += yy, m.syz += yz, m.szz += zz;
            }
          }
          for (std::size_t r = 0; r < scales; ++r) {
            const double variation = moments[r].surface_variation();
            if (std::isfinite(variation)) out[r][i] = float(variation) * kSurfaceVariationScale;
          }
        }
      });
  throw_if_stopped(context.stop, "multi-scale features");
  return out;
}
}  // namespace

Descriptors multi_scale_input(const PointCloud& cloud, Descriptors descriptors,
                              const FeatureSettings& settings, const NeighborSearch& search,
                              bool curvature_at_normal_radius, std::span<const std::uint8_t> wanted,
                              const RunContext& context) {
  if (!settings.multi_scale()) return descriptors;
  const std::size_t n = cloud.size();
  const int d = settings.descriptor_dim();
  // One search a point at the largest radius, shared by every further FPFH and every variation.
  float widest = settings.features.radius;
  for (float radius : settings.extra_feature_radii) widest = std::max(widest, radius);
  if (settings.surface_variation_features) widest = std::max(widest, settings.normals.radius);
  // Only the described points' lists and their neighbours' (the plane cascade leaves most out).
  const NeighborLists lists(cloud.xyz, search, capped(Neighborhood::Radius(widest)), kListBytes,
                            wanted, context);

  std::vector<Descriptors> blocks;
  blocks.push_back(std::move(descriptors));
  for (float radius : settings.extra_feature_radii) {
    FeatureOptions options;
    options.neighborhood = capped(Neighborhood::Radius(radius));
    options.fpfh_variant = settings.fpfh_variant;
    options.wanted = wanted;
    blocks.push_back(compute_fpfh(cloud, options, context, {.search = &search, .lists = &lists}));
  }
  // Variations at the normal radius (estimate_normals' curvature when it ran at that radius),
  // the feature radius and the further radii, in that order.
  std::vector<const std::vector<float>*> variations;
  std::vector<std::vector<float>> measured;
  std::vector<float> at_normal_radius;
  if (settings.surface_variation_features) {
    std::vector<float> ascending = {settings.features.radius};
    ascending.insert(ascending.end(), settings.extra_feature_radii.begin(),
                     settings.extra_feature_radii.end());
    if (!curvature_at_normal_radius) ascending.push_back(settings.normals.radius);
    std::sort(ascending.begin(), ascending.end());
    ascending.erase(std::unique(ascending.begin(), ascending.end()), ascending.end());
    measured = scaled_variations(cloud.xyz, ascending, lists, wanted, context);
    const auto at = [&](float radius) {
      return &measured[std::size_t(std::lower_bound(ascending.begin(), ascending.end(), radius) -
                                   ascending.begin())];
    };
    if (curvature_at_normal_radius) {
      at_normal_radius.resize(n, 0.0f);
      for (std::size_t i = 0; i < n; ++i)
        if (i < cloud.curvature.size() && std::isfinite(cloud.curvature[i]))
          at_normal_radius[i] = cloud.curvature[i] * kSurfaceVariationScale;
      variations.push_back(&at_normal_radius);
    } else {
      variations.push_back(at(settings.normals.radius));
    }
    variations.push_back(at(settings.features.radius));
    for (float radius : settings.extra_feature_radii) variations.push_back(at(radius));
  }

  const int dim = settings.scale_input_dim();
  Descriptors out = Descriptors::filled(n, dim, std::numeric_limits<float>::quiet_NaN());
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(blocks[0].row(i)[0])) continue;  // no descriptor: stays invalid
    std::span<float> row = out.row(i);
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      const std::span<const float> part = blocks[b].row(i);
      std::copy(part.begin(), part.end(), row.begin() + std::ptrdiff_t(b) * d);
    }
    const std::size_t tail = blocks.size() * std::size_t(d);
    for (std::size_t v = 0; v < variations.size(); ++v) row[tail + v] = (*variations[v])[i];
    // An extra scale can be NaN where the first is not only through a NaN normal, which the
    // first would share; zero keeps the row usable all the same.
    for (float& value : row)
      if (!std::isfinite(value)) value = 0.0f;
  }
  return out;
}

Descriptors leading_values(Descriptors descriptors, int dim) {
  if (descriptors.dim <= dim) return descriptors;
  const std::size_t n = descriptors.size();
  Descriptors out(dim, std::vector<float>(n * std::size_t(dim)));
  for (std::size_t i = 0; i < n; ++i) {
    const std::span<const float> row = descriptors.row(i);
    std::copy(row.begin(), row.begin() + dim, out.row(i).begin());
  }
  return out;
}

}  // namespace primlabel::pipeline
