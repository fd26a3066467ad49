// The only translation unit of `primlabel-bench tabletop` that includes PCL.

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
#if __has_include(<pcl/segmentation/lccp_segmentation.h>)
#include <pcl/segmentation/lccp_segmentation.h>
#include <pcl/segmentation/supervoxel_clustering.h>
#define PRIMLABEL_PCL_HAS_LCCP 1
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

namespace primlabel::bench {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

std::string pcl_tabletop_version() { return PCL_VERSION_PRETTY; }

bool pcl_has_lccp() {
#ifdef PRIMLABEL_PCL_HAS_LCCP
  return true;
#else
  return false;
#endif
}

namespace {

#ifdef PRIMLABEL_PCL_HAS_LCCP
// LCCP (Stein et al. 2014) on supervoxels (Papon et al. 2013) of the object points, with the
// parameters of PCL's LCCP example, except the voxel resolution at the Kinect's spacing at 1 m.
std::vector<pcl::PointIndices> lccp_clusters(const PointCloud& input, const Cloud& finite,
                                             const pcl::Indices& to_input,
                                             const pcl::Indices& objects, int min_size) {
  using PointT = pcl::PointXYZRGBA;
  pcl::PointCloud<PointT>::Ptr points(new pcl::PointCloud<PointT>);
  points->reserve(objects.size());
  // In the sensor's frame, which the single-camera transform assumes (a scan saved in a world
  // frame would otherwise be distorted, and can trip the octree's bounds assertion).
  const Eigen::Matrix3f to_sensor =
      input.viewpoint.orientation.normalized().toRotationMatrix().transpose();
  for (pcl::index_t i : objects) {
    PointT p;
    const Vec3f q =
        to_sensor * (Vec3f(finite[i].x, finite[i].y, finite[i].z) - input.viewpoint.origin);
    p.x = q.x();
    p.y = q.y();
    p.z = q.z();
    const std::uint32_t rgb = input.has_rgba() ? input.rgba[to_input[i]] : 0x808080u;
    p.r = (rgb >> 16) & 0xFF;
    p.g = (rgb >> 8) & 0xFF;
    p.b = rgb & 0xFF;
    p.a = 255;
    points->push_back(p);
  }
  pcl::SupervoxelClustering<PointT> supervoxels(0.0075f, 0.03f);
  supervoxels.setUseSingleCameraTransform(true);  // a Kinect's depth-dependent voxels
  supervoxels.setInputCloud(points);
  supervoxels.setColorImportance(0.0f);
  supervoxels.setSpatialImportance(1.0f);
  supervoxels.setNormalImportance(4.0f);
  std::map<std::uint32_t, pcl::Supervoxel<PointT>::Ptr> clusters;
  supervoxels.extract(clusters);
  std::multimap<std::uint32_t, std::uint32_t> adjacency;
  supervoxels.getSupervoxelAdjacency(adjacency);

  pcl::LCCPSegmentation<PointT> lccp;
  lccp.setConcavityToleranceThreshold(10.0f);
  lccp.setSanityCheck(true);
  lccp.setSmoothnessCheck(true, 0.0075f, 0.03f, 0.1f);
  lccp.setKFactor(0);
  lccp.setInputSupervoxels(clusters, adjacency);
  lccp.setMinSegmentSize(0);
  lccp.segment();
  pcl::PointCloud<pcl::PointXYZL>::Ptr supervoxel_labels = supervoxels.getLabeledCloud();
  pcl::PointCloud<pcl::PointXYZL>::Ptr labeled = supervoxel_labels->makeShared();
  lccp.relabelCloud(*labeled);

  // The labeled cloud lists the input points in order; label 0 is "unassigned".
  std::map<std::uint32_t, pcl::PointIndices> by_label;
  for (std::size_t k = 0; k < labeled->size() && k < objects.size(); ++k)
    if ((*labeled)[k].label != 0) by_label[(*labeled)[k].label].indices.push_back(objects[k]);
  std::vector<pcl::PointIndices> result;
  for (auto& [label, members] : by_label)
    if (static_cast<int>(members.indices.size()) >= min_size) result.push_back(std::move(members));
  return result;
}
#endif

enum class Clustering { kEuclidean, kLccp };

PclTabletopResult run_pipeline(const PointCloud& input, const PclTabletopOptions& options,
                               Clustering clustering) {
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
  // RANSAC, as PCL's table-top tutorials: PCL 1.13's MSAC keeps a first hypothesis outside the
  // angle (empty distances, zero penalty; msac.hpp skips those only once k > 1) and then fails
  // with "Estimated distances (0) differs ...", so it finds no table on many tilted frames.
  sac.setMethodType(pcl::SAC_RANSAC);
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
  // Heights are counted toward the sensor side of the plane.
  prism.setViewPoint(input.viewpoint.origin.x(), input.viewpoint.origin.y(),
                     input.viewpoint.origin.z());
  pcl::PointIndices::Ptr objects(new pcl::PointIndices);
  prism.segment(*objects);

  std::vector<pcl::PointIndices> clusters;
#ifdef PRIMLABEL_PCL_HAS_LCCP
  if (clustering == Clustering::kLccp && !objects->indices.empty())
    clusters = lccp_clusters(input, *finite, to_input, objects->indices, options.min_cluster_size);
#endif
  if (clustering == Clustering::kEuclidean && !objects->indices.empty()) {
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

}  // namespace

PclTabletopResult pcl_tabletop(const PointCloud& input, const PclTabletopOptions& options) {
  return run_pipeline(input, options, Clustering::kEuclidean);
}

PclTabletopResult pcl_lccp(const PointCloud& input, const PclTabletopOptions& options) {
  return run_pipeline(input, options, Clustering::kLccp);
}

}  // namespace primlabel::bench
