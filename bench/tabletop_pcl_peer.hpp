#pragma once
// PCL's classic table-top pipeline as a peer for `primlabel-bench tabletop`: SACSegmentation
// (RANSAC, plane perpendicular to the up axis), ConvexHull of the projected inliers,
// ExtractPolygonalPrismData and EuclideanClusterExtraction (or LCCP), with the same thresholds as
// primlabel's filter. PCL-free interface; tabletop_pcl_peer.cpp is the only file including PCL.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::bench {

struct PclTabletopOptions {
  Vec3f axis = Vec3f(0, -1, 0);  // up prior
  float max_angle_deg = 60.0f;   // plane normal within this of the axis
  float distance_threshold = 0.01f;
  int max_iterations = 1000;
  double probability = 0.999;
  float table_band = 0.006f;  // prism: objects from this height...
  float max_height = 0.5f;    // ...up to this
  float cluster_tolerance = 0.02f;
  int min_cluster_size = 100;
  int max_cluster_size = 200000;
};

struct PclTabletopResult {
  bool found = false;
  Eigen::Vector4f plane = Eigen::Vector4f::Zero();
  std::vector<std::uint32_t> table_inliers;          // input indices, ascending
  std::vector<std::vector<std::uint32_t>> clusters;  // input indices
  double ms = 0.0;  // NaN removal through clustering; copy into PCL's point type excluded
};

// Runs the pipeline on `cloud` (NaN points allowed; they are removed as part of the timing).
PclTabletopResult pcl_tabletop(const PointCloud& cloud, const PclTabletopOptions& options);

// The same table and prism, but the objects are LCCP segments of supervoxels (Stein et al. 2014,
// PCL's LCCPSegmentation) instead of Euclidean clusters. Only when pcl_has_lccp().
PclTabletopResult pcl_lccp(const PointCloud& input, const PclTabletopOptions& options);
bool pcl_has_lccp();

std::string pcl_tabletop_version();

}  // namespace primlabel::bench
