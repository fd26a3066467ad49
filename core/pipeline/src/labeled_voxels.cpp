// Voxel centroids with the majority label of their members (pipeline/labeled_voxels.hpp).

#include "primlabel/pipeline/labeled_voxels.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::pipeline {

namespace {

// The most frequent of `labels` (sorted in place); ties go to the lowest id.
std::uint32_t majority(std::vector<std::uint32_t>& labels) {
  std::sort(labels.begin(), labels.end());
  std::uint32_t best = labels.front();
  std::size_t best_count = 0;
  for (std::size_t i = 0; i < labels.size();) {
    std::size_t j = i;
    while (j < labels.size() && labels[j] == labels[i]) ++j;
    if (j - i > best_count) {  // strictly more: an equal count keeps the lower id found first
      best = labels[i];
      best_count = j - i;
    }
    i = j;
  }
  return best;
}

}  // namespace

PointCloud voxelize_labeled(const PointCloud& cloud, float voxel_size, const RunContext& context) {
  if (!(voxel_size > 0.0f) || !std::isfinite(voxel_size))
    throw std::invalid_argument("voxel size must be finite and > 0");
  if (cloud.labels.size() != cloud.size())
    throw std::invalid_argument("voxelize_labeled: the cloud has " +
                                std::to_string(cloud.labels.size()) + " labels for " +
                                std::to_string(cloud.size()) + " points");
  const tabletop::VoxelGrid grid = tabletop::voxel_downsample(
      cloud.xyz, tabletop::finite_indices(cloud.xyz), voxel_size, context);
  PointCloud voxels;
  voxels.resize_unorganized(grid.centroids.size());
  voxels.xyz = grid.centroids;
  voxels.viewpoint = cloud.viewpoint;
  voxels.labels.resize(grid.centroids.size());
  std::vector<std::uint32_t> member_labels;
  for (std::size_t v = 0; v < grid.centroids.size(); ++v) {
    member_labels.clear();
    for (std::uint32_t m = grid.member_offsets[v]; m < grid.member_offsets[v + 1]; ++m)
      member_labels.push_back(cloud.labels[grid.members[m]]);
    voxels.labels[v] = majority(member_labels);
  }
  return voxels;
}

}  // namespace primlabel::pipeline
