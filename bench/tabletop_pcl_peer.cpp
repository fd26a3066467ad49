// The only translation unit of primlabel-bench-tabletop that includes PCL.

#include "tabletop_pcl_peer.hpp"

#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/common/io.h>
#include <pcl/filters/filter.h>
#include <pcl/filters/project_inliers.h>
#include <pcl/pcl_config.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/extract_polygonal_prism_data.h>
#include <pcl/segmentation/sac_segmentation.h>
#include <pcl/surface/convex_hull.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace primlabel::bench {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

std::string pcl_tabletop_version() { return PCL_VERSION_PRETTY; }

PclTabletopResult pcl_tabletop(const PointCloud& input, const PclTabletopOptions& options) {
  PclTabletopResult result;
  Cloud::Ptr cloud(new Cloud);
  cloud->resize(input.size());
  for (std::size_t i = 0; i < input.size(); ++i)
    (*cloud)[i] = pcl::PointXYZ(input.xyz[i].x(), input.xyz[i].y(), input.xyz[i].z());
  cloud->width = input.width;
  cloud->height = input.height;
  cloud->is_dense = false;

  const auto start = std::chrono::steady_clock::now();
  Cloud::Ptr finite(new Cloud);
  pcl::Indices to_input;
  pcl::removeNaNFromPointCloud(*cloud, *finite, to_input);

  pcl::SACSegmentation<pcl::PointXYZ> sac;
  sac.setOptimizeCoefficients(true);
  sac.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);
  sac.setMethodType(pcl::SAC_MSAC);
  sac.setDistanceThreshold(options.distance_threshold);
  sac.setAxis(options.axis.normalized());
  sac.setEpsAngle(options.max_angle_deg * M_PI / 180.0);
  sac.setMaxIterations(options.max_iterations);
  sac.setProbability(options.probability);
  sac.setInputCloud(finite);
  pcl::PointIndices::Ptr inliers(new pcl::PointIndices);
  pcl::ModelCoefficients::Ptr coefficients(new pcl::ModelCoefficients);
  sac.segment(*inliers, *coefficients);
  if (inliers->indices.size() < 3 || coefficients->values.size() != 4) {
    result.ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  }
  result.found = true;
  for (int k = 0; k < 4; ++k) result.plane[k] = coefficients->values[k];

  // Table boundary: 2D convex hull of the inliers projected onto the plane.
  pcl::ProjectInliers<pcl::PointXYZ> project;
  project.setModelType(pcl::SACMODEL_PLANE);
  project.setInputCloud(finite);
  project.setIndices(inliers);
  project.setModelCoefficients(coefficients);
  Cloud::Ptr projected(new Cloud);
  project.filter(*projected);
  pcl::ConvexHull<pcl::PointXYZ> hull;
  hull.setDimension(2);
  hull.setInputCloud(projected);
  Cloud::Ptr hull_points(new Cloud);
  hull.reconstruct(*hull_points);

  // Objects: above the plane inside the hull's prism, then Euclidean clusters.
  pcl::ExtractPolygonalPrismData<pcl::PointXYZ> prism;
  prism.setInputCloud(finite);
  prism.setInputPlanarHull(hull_points);
  prism.setHeightLimits(options.table_band, options.max_height);
  prism.setViewPoint(0, 0, 0);  // heights are counted toward the sensor side of the plane
  pcl::PointIndices::Ptr objects(new pcl::PointIndices);
  prism.segment(*objects);

  std::vector<pcl::PointIndices> clusters;
  if (!objects->indices.empty()) {
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    tree->setInputCloud(finite, std::make_shared<pcl::Indices>(objects->indices));
    pcl::EuclideanClusterExtraction<pcl::PointXYZ> extract;
    extract.setClusterTolerance(options.cluster_tolerance);
    extract.setMinClusterSize(options.min_cluster_size);
    extract.setMaxClusterSize(options.max_cluster_size);
    extract.setSearchMethod(tree);
    extract.setInputCloud(finite);
    extract.setIndices(objects);
    extract.extract(clusters);
  }
  result.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  for (pcl::index_t i : inliers->indices) result.table_inliers.push_back(to_input[i]);
  std::sort(result.table_inliers.begin(), result.table_inliers.end());
  for (const pcl::PointIndices& c : clusters) {
    std::vector<std::uint32_t> members;
    for (pcl::index_t i : c.indices) members.push_back(to_input[i]);
    std::sort(members.begin(), members.end());
    result.clusters.push_back(std::move(members));
  }
  return result;
}

}  // namespace primlabel::bench
