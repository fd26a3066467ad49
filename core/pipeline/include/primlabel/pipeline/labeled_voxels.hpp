#pragma once
// Training at a model's voxel size: a labeled cloud downsampled the way label_cloud downsamples
// what it labels (tabletop::voxel_downsample, one centroid per voxel), so a model with
// FeatureSettings.voxel_size is trained on the density it is served at.

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::pipeline {

// One point per occupied voxel of edge `voxel_size` over the finite points of `cloud`, at the
// members' centroid, labeled with the members' most frequent label (a tie goes to the lowest
// id, so the result does not depend on point order). Unorganised, same viewpoint, no normals.
// Throws std::invalid_argument when the cloud has no label per point or voxel_size <= 0, and
// what tabletop::voxel_downsample throws (an extent too large for the grid, Cancelled).
PointCloud voxelize_labeled(const PointCloud& cloud, float voxel_size,
                            const RunContext& context = {});

}  // namespace primlabel::pipeline
