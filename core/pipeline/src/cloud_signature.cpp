#include "primlabel/pipeline/cloud_signature.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "primlabel/geometry/neighbor_search.hpp"

namespace primlabel::pipeline {
namespace {

// The upper median (NaN for none); reorders `values`.
float median_of(std::vector<float>& values) {
  if (values.empty()) return std::numeric_limits<float>::quiet_NaN();
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// RMS distance of the points to their least-squares plane: the root of the smallest eigenvalue
// of their covariance. In double, centred first, so far-away patches keep their millimetres.
float plane_rms(const std::vector<Vec3f>& xyz, const NeighborList& patch) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::uint32_t j : patch.indices) mean += xyz[j].cast<double>();
  mean /= double(patch.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::uint32_t j : patch.indices) {
    const Eigen::Vector3d d = xyz[j].cast<double>() - mean;
    covariance += d * d.transpose();
  }
  covariance /= double(patch.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance, Eigen::EigenvaluesOnly);
  return float(std::sqrt(std::max(0.0, solver.eigenvalues()(0))));
}

}  // namespace

CloudSignature measure_signature(const std::vector<Vec3f>& xyz, const RunContext& context,
                                 std::size_t max_samples) {
  const NeighborSearch search(xyz, context.stop);
  std::size_t finite = 0;
  for (const Vec3f& p : xyz) finite += is_finite(p) ? 1 : 0;
  // Every stride-th finite point, so invalid pixels of a frame do not change the sample.
  const std::size_t stride =
      std::max<std::size_t>(1, finite / std::max<std::size_t>(1, max_samples));
  // The nearest distinct point: the query itself and coincident copies come first at 0.
  const Neighborhood nearest = Neighborhood::Knn(8);
  // A patch is read whole but at most this many points of it: a dense scan's 10 mm holds
  // thousands, and the nearest few hundred already fix the plane.
  const Neighborhood patch_hood = Neighborhood::Hybrid(kRoughnessRadius, 256);
  std::vector<float> spacing, roughness;
  NeighborList found;
  std::size_t seen = 0;
  for (const Vec3f& p : xyz) {
    if (!is_finite(p)) continue;
    if (seen++ % stride != 0) continue;
    search.find(p, nearest, found);
    for (float sq : found.sq_dists)
      if (sq > 0.0f) {
        spacing.push_back(std::sqrt(sq));
        break;
      }
    search.find(p, patch_hood, found, false);
    if (found.size() >= kRoughnessMinPoints) roughness.push_back(plane_rms(xyz, found));
    context.throw_if_stopped("measuring the cloud");
  }
  CloudSignature signature;
  signature.point_spacing = median_of(spacing);
  signature.roughness = median_of(roughness);
  return signature;
}

}  // namespace primlabel::pipeline
