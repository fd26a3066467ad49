#include "primlabel/tabletop/table_noise.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace primlabel::tabletop {

void TableNoiseOptions::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (!(depth_noise_per_m2 >= 0.0f) || !std::isfinite(depth_noise_per_m2))
    fail("table noise depth coefficient must be >= 0, got " + std::to_string(depth_noise_per_m2));
  if (!(noise_sigmas >= 0.0f) || !std::isfinite(noise_sigmas))
    fail("table noise sigmas must be >= 0, got " + std::to_string(noise_sigmas));
  if (!(min_share_in_band > 0.0f && min_share_in_band <= 1.0f))
    fail("table noise share must be in (0, 1], got " + std::to_string(min_share_in_band));
}

float table_noise_band(const TableNoiseOptions& options, float floor_band, float range) {
  return std::max(floor_band, options.noise_sigmas * options.depth_noise_per_m2 * range * range);
}

TableNoiseSplit separate_table_noise(const std::vector<Vec3f>& points,
                                     const std::vector<float>& height, const Vec3f& sensor,
                                     std::vector<std::vector<std::uint32_t>> clusters,
                                     float floor_band, const TableNoiseOptions& options) {
  options.validate();
  TableNoiseSplit split;
  if (!options.enabled) {
    split.objects = std::move(clusters);
    return split;
  }
  for (auto& cluster : clusters) {
    std::size_t in_band = 0;
    for (std::uint32_t i : cluster) {
      in_band +=
          std::abs(height[i]) <= table_noise_band(options, floor_band, (points[i] - sensor).norm());
    }
    if (!cluster.empty() &&
        double(in_band) >= double(options.min_share_in_band) * double(cluster.size()))
      split.table_points.insert(split.table_points.end(), cluster.begin(), cluster.end());
    else
      split.objects.push_back(std::move(cluster));
  }
  std::sort(split.table_points.begin(), split.table_points.end());
  return split;
}

}  // namespace primlabel::tabletop
