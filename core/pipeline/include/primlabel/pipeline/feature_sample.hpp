#pragma once
// The sample FPFH neighbourhoods are drawn from when FeatureSettings.feature_sample_size > 0:
// one point of the cloud per occupied voxel, so a dense scan's descriptor sees ~a few hundred
// neighbours instead of ~700 while every point keeps its own descriptor (and its own label).

#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::pipeline {

// A copy of `points` in which only one point per occupied voxel of edge `leaf` stays finite:
// the member nearest its voxel's centroid (ties to the lowest index, so the choice does not
// depend on point order or threads); every other entry is NaN. Indexing the copy with a
// NeighborSearch gives neighbour lists over the sample in the cloud's own indices.
// Throws std::invalid_argument when leaf is not finite and > 0, and what
// tabletop::voxel_downsample throws (an extent too large for the grid, Cancelled).
std::vector<Vec3f> voxel_sample(const std::vector<Vec3f>& points, float leaf,
                                const RunContext& context = {});

}  // namespace primlabel::pipeline
