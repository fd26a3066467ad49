// One representative point per voxel for the FPFH neighbourhoods (pipeline/feature_sample.hpp).

#include "primlabel/pipeline/feature_sample.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::pipeline {

std::vector<Vec3f> voxel_sample(const std::vector<Vec3f>& points, float leaf,
                                const RunContext& context) {
  if (!(leaf > 0.0f) || !std::isfinite(leaf))
    throw std::invalid_argument("feature sample size must be finite and > 0");
  const tabletop::VoxelGrid grid =
      tabletop::voxel_downsample(points, tabletop::finite_indices(points), leaf, context);
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  std::vector<Vec3f> sample(points.size(), Vec3f::Constant(kNaN));
  for (std::size_t v = 0; v < grid.centroids.size(); ++v) {
    std::uint32_t best = grid.members[grid.member_offsets[v]];
    float best_sq = std::numeric_limits<float>::infinity();
    // Members are ascending, and only a strictly nearer one replaces the best.
    for (std::uint32_t m = grid.member_offsets[v]; m < grid.member_offsets[v + 1]; ++m) {
      const float sq = (points[grid.members[m]] - grid.centroids[v]).squaredNorm();
      if (sq < best_sq) best = grid.members[m], best_sq = sq;
    }
    sample[best] = points[best];
  }
  return sample;
}

}  // namespace primlabel::pipeline
