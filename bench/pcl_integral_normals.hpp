#pragma once
// PCL's IntegralImageNormalEstimation as the peer of `primlabel-bench organised`'s integral-image
// normals, on the same organised frame. This interface is PCL-free; pcl_integral_normals.cpp is
// compiled only in a build with PCL (bench/CMakeLists.txt).

#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::bench {

struct PclPixelNormals {
  std::vector<Vec3f> normals;  // per pixel; NaN where PCL gave none
  double seconds = 0.0;        // best of the repeats
};

// pcl::IntegralImageNormalEstimation<PointXYZ, Normal> on `frame` (organised), with PCL's
// tutorial settings: max depth change factor 0.02, normal smoothing size 10, depth-dependent
// smoothing; `method` is "average_3d_gradient" or "covariance_matrix".
PclPixelNormals pcl_integral_normals(const PointCloud& frame, const std::string& method,
                                     int repeat);

}  // namespace primlabel::bench
