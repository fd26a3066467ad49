// Includes PCL: built only where PCL is found (see pcl_integral_normals.hpp).

#include "pcl_integral_normals.hpp"

#include <pcl/features/integral_image_normal.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>

namespace primlabel::bench {

PclPixelNormals pcl_integral_normals(const PointCloud& frame, const std::string& method,
                                     int repeat) {
  if (!frame.organized()) throw std::invalid_argument("PCL integral normals: not organised");
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->width = frame.width;
  cloud->height = frame.height;
  cloud->is_dense = false;
  cloud->points.resize(frame.size());
  for (std::size_t i = 0; i < frame.size(); ++i)
    cloud->points[i] = pcl::PointXYZ(frame.xyz[i].x(), frame.xyz[i].y(), frame.xyz[i].z());
  cloud->sensor_origin_ = Eigen::Vector4f(frame.viewpoint.origin.x(), frame.viewpoint.origin.y(),
                                          frame.viewpoint.origin.z(), 0.0f);
  cloud->sensor_orientation_ = frame.viewpoint.orientation;

  using Estimation = pcl::IntegralImageNormalEstimation<pcl::PointXYZ, pcl::Normal>;
  Estimation estimation;
  if (method == "average_3d_gradient")
    estimation.setNormalEstimationMethod(Estimation::AVERAGE_3D_GRADIENT);
  else if (method == "covariance_matrix")
    estimation.setNormalEstimationMethod(Estimation::COVARIANCE_MATRIX);
  else
    throw std::invalid_argument("PCL integral normals: unknown method " + method);
  estimation.setMaxDepthChangeFactor(0.02f);
  estimation.setNormalSmoothingSize(10.0f);
  estimation.setDepthDependentSmoothing(true);
  estimation.setViewPoint(frame.viewpoint.origin.x(), frame.viewpoint.origin.y(),
                          frame.viewpoint.origin.z());
  estimation.setInputCloud(cloud);

  pcl::PointCloud<pcl::Normal> normals;
  PclPixelNormals out;
  out.seconds = std::numeric_limits<double>::infinity();
  for (int r = 0; r < std::max(1, repeat); ++r) {
    const auto start = std::chrono::steady_clock::now();
    estimation.compute(normals);
    out.seconds =
        std::min(out.seconds,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  out.normals.resize(normals.size());
  for (std::size_t i = 0; i < normals.size(); ++i)
    out.normals[i] = Vec3f(normals[i].normal_x, normals[i].normal_y, normals[i].normal_z);
  return out;
}

}  // namespace primlabel::bench
