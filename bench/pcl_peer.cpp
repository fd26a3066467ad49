// The only translation unit of the bench that includes PCL (see pcl_peer.hpp).

#include "pcl_peer.hpp"

#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/pcl_config.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>

namespace primlabel::bench {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Feature estimators take either a radius or a k, never both (PCL refuses hybrid searches).
template <typename Estimator>
void apply_neighborhood(Estimator& estimator, const Neighborhood& hood) {
  if (!hood.valid() || hood.max_neighbors > 0)
    throw std::invalid_argument("PCL peer: needs a pure radius or k-NN neighbourhood, got " +
                                hood.describe());
  if (hood.k > 0)
    estimator.setKSearch(hood.k);
  else
    estimator.setRadiusSearch(hood.radius);
}

// Runs estimator.compute() `repeat` times and returns the fastest wall time.
template <typename Estimator, typename Output>
double best_compute_seconds(Estimator& estimator, Output& output, int repeat) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < std::max(1, repeat); ++r) {
    const auto start = Clock::now();
    estimator.compute(output);
    best = std::min(best, seconds_since(start));
  }
  return best;
}

}  // namespace

struct PclPeer::Impl {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud;
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree;
  double index_seconds = 0.0;
};

PclPeer::PclPeer(const std::vector<Vec3f>& points) : impl_(std::make_unique<Impl>()) {
  impl_->cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  impl_->cloud->resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    (*impl_->cloud)[i] = pcl::PointXYZ(points[i].x(), points[i].y(), points[i].z());
  impl_->cloud->is_dense = true;  // the caller passes finite points only

  // Sorted results (ascending distance) as primlabel's NeighborSearch returns them: the FPFH
  // weighting sums neighbours in list order, so the order decides the last bits of the result.
  // Feature::initCompute only rebuilds a tree whose input is not the estimator's surface, so this
  // tree is built exactly once, here.
  const auto start = Clock::now();
  impl_->tree = std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>(true);
  impl_->tree->setInputCloud(impl_->cloud);
  impl_->index_seconds = seconds_since(start);
}

PclPeer::~PclPeer() = default;

double PclPeer::index_seconds() const { return impl_->index_seconds; }

PclNormals PclPeer::estimate_normals(const Neighborhood& hood, const Vec3f& viewpoint, int threads,
                                     int repeat) {
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> estimator;
  estimator.setInputCloud(impl_->cloud);
  estimator.setSearchMethod(impl_->tree);
  apply_neighborhood(estimator, hood);
  estimator.setViewPoint(viewpoint.x(), viewpoint.y(), viewpoint.z());
  estimator.setNumberOfThreads(static_cast<unsigned int>(std::max(0, threads)));

  pcl::PointCloud<pcl::Normal> output;
  PclNormals result;
  result.seconds = best_compute_seconds(estimator, output, repeat);
  result.normals.resize(output.size());
  result.curvature.resize(output.size());
  for (std::size_t i = 0; i < output.size(); ++i) {
    result.normals[i] = Vec3f(output[i].normal_x, output[i].normal_y, output[i].normal_z);
    result.curvature[i] = output[i].curvature;
  }
  return result;
}

PclFpfh PclPeer::compute_fpfh(const std::vector<Vec3f>& normals, const Neighborhood& hood,
                              int threads, int repeat) {
  if (normals.size() != impl_->cloud->size())
    throw std::invalid_argument("PCL peer: one normal per point is required for FPFH");
  auto pcl_normals = std::make_shared<pcl::PointCloud<pcl::Normal>>();
  pcl_normals->resize(normals.size());
  for (std::size_t i = 0; i < normals.size(); ++i)
    (*pcl_normals)[i] = pcl::Normal(normals[i].x(), normals[i].y(), normals[i].z());

  pcl::FPFHEstimationOMP<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> estimator;
  estimator.setInputCloud(impl_->cloud);
  estimator.setInputNormals(pcl_normals);
  estimator.setSearchMethod(impl_->tree);
  apply_neighborhood(estimator, hood);
  estimator.setNumberOfThreads(static_cast<unsigned int>(std::max(0, threads)));

  pcl::PointCloud<pcl::FPFHSignature33> output;
  PclFpfh result;
  result.seconds = best_compute_seconds(estimator, output, repeat);
  constexpr std::size_t kBins = 33;
  result.descriptors.resize(output.size() * kBins);
  for (std::size_t i = 0; i < output.size(); ++i)
    std::copy_n(output[i].histogram, kBins, result.descriptors.begin() + i * kBins);
  return result;
}

std::string PclPeer::version() { return PCL_VERSION_PRETTY; }

}  // namespace primlabel::bench
