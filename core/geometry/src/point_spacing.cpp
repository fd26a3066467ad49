#include "primlabel/geometry/point_spacing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace primlabel {
namespace {

// Every stride-th element gives at most max_samples of n.
std::size_t sample_stride(std::size_t n, std::size_t max_samples) {
  return std::max<std::size_t>(1, n / std::max<std::size_t>(1, max_samples));
}

// The upper median (NaN for none); reorders `values`.
float median_of(std::vector<float>& values) {
  if (values.empty()) return std::numeric_limits<float>::quiet_NaN();
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace

float median_point_spacing(const std::vector<Vec3f>& xyz, const NeighborSearch& search,
                           std::size_t max_samples) {
  const std::size_t stride = sample_stride(xyz.size(), max_samples);
  // The query point itself and a few coincident copies come first at distance 0.
  const Neighborhood nearest = Neighborhood::Knn(8);
  std::vector<float> spacing;
  NeighborList found;
  for (std::size_t i = 0; i < xyz.size(); i += stride) {
    if (!is_finite(xyz[i])) continue;
    search.find(xyz[i], nearest, found);
    for (float sq : found.sq_dists)
      if (sq > 0.0f) {
        spacing.push_back(std::sqrt(sq));
        break;
      }
  }
  return median_of(spacing);
}

float median_surface_variation(const std::vector<float>& curvature, std::size_t max_samples) {
  const std::size_t stride = sample_stride(curvature.size(), max_samples);
  std::vector<float> values;
  for (std::size_t i = 0; i < curvature.size(); i += stride)
    if (std::isfinite(curvature[i])) values.push_back(curvature[i]);
  return median_of(values);
}

}  // namespace primlabel
