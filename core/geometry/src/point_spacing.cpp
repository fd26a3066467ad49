#include "primlabel/geometry/point_spacing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace primlabel {

float median_point_spacing(const std::vector<Vec3f>& xyz, const NeighborSearch& search,
                           std::size_t max_samples) {
  const std::size_t stride =
      std::max<std::size_t>(1, xyz.size() / std::max<std::size_t>(1, max_samples));
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
  if (spacing.empty()) return std::numeric_limits<float>::quiet_NaN();
  const auto middle = spacing.begin() + spacing.size() / 2;
  std::nth_element(spacing.begin(), middle, spacing.end());
  return *middle;
}

float median_surface_variation(const std::vector<float>& curvature, std::size_t max_samples) {
  const std::size_t stride =
      std::max<std::size_t>(1, curvature.size() / std::max<std::size_t>(1, max_samples));
  std::vector<float> values;
  for (std::size_t i = 0; i < curvature.size(); i += stride)
    if (std::isfinite(curvature[i])) values.push_back(curvature[i]);
  if (values.empty()) return std::numeric_limits<float>::quiet_NaN();
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace primlabel
