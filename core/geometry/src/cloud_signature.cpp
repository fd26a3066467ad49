#include "primlabel/geometry/cloud_signature.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "primlabel/geometry/neighbor_search.hpp"

namespace primlabel {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The value at `fraction` of the sorted order (upper for the median); NaN for none. Reorders.
float quantile_of(std::vector<float>& values, double fraction) {
  if (values.empty()) return kNaN;
  const auto at = values.begin() + std::ptrdiff_t(fraction * double(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), at, values.end());
  return *at;
}

struct PatchFit {
  float rms = 0;             // RMS distance of the points to their least-squares plane
  Eigen::Vector3d normal{};  // of that plane
  Eigen::Vector3d centre{};
};

// The least-squares plane: the eigenvector of the smallest eigenvalue of the covariance, whose
// root is the RMS distance. In double, centred first, so far-away patches keep their millimetres.
PatchFit fit_patch(const std::vector<Vec3f>& xyz, const NeighborList& patch) {
  PatchFit fit;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::uint32_t j : patch.indices) mean += xyz[j].cast<double>();
  mean /= double(patch.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::uint32_t j : patch.indices) {
    const Eigen::Vector3d d = xyz[j].cast<double>() - mean;
    covariance += d * d.transpose();
  }
  covariance /= double(patch.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  fit.rms = float(std::sqrt(std::max(0.0, solver.eigenvalues()(0))));
  fit.normal = solver.eigenvectors().col(0);
  fit.centre = mean;
  return fit;
}

// Below this cosine between the viewing ray and a patch's normal, a patch is seen too obliquely
// for its roughness to tell the noise along the ray.
constexpr double kMinViewingCosine = 0.3;

// g in noise ~ range^g from (range, noise along the ray) pairs: the near and far halves by range,
// each summarised by its median range and the lower quartile of its noise.
float noise_growth(std::vector<std::pair<float, float>> patches) {
  if (patches.size() < 16) return kNaN;
  std::sort(patches.begin(), patches.end());
  const std::size_t half = patches.size() / 2;
  auto summary = [&](std::size_t first, std::size_t last) {
    std::vector<float> ranges, roughness;
    for (std::size_t i = first; i < last; ++i) {
      ranges.push_back(patches[i].first);
      roughness.push_back(patches[i].second);
    }
    return std::pair{quantile_of(ranges, 0.5), quantile_of(roughness, 0.25)};
  };
  const auto [near_range, near_roughness] = summary(0, half);
  const auto [far_range, far_roughness] = summary(half, patches.size());
  if (!(near_range > 0.0f) || far_range < near_range * kNoiseGrowthMinRangeRatio ||
      !(near_roughness > 0.0f) || !(far_roughness > 0.0f))
    return kNaN;
  return float(std::log(double(far_roughness) / near_roughness) /
               std::log(double(far_range) / near_range));
}

// Whether at least 90% of `values` lie on one decimal grid (0.01 down to 1e-5): coordinates
// rounded for storage (a text file with three decimals) tie in every axis, which is no sensor's
// depth quantisation.
bool on_a_decimal_grid(const std::vector<float>& values) {
  if (values.empty()) return false;
  for (const double step : {1e-2, 1e-3, 1e-4, 1e-5}) {
    std::size_t on = 0;
    for (float v : values) {
      const double cells = double(v) / step;
      on += std::abs(cells - std::round(cells)) < 0.01 ? 1 : 0;
    }
    if (on >= values.size() * 9 / 10) return true;
  }
  return false;
}

}  // namespace

CloudSignature measure_signature(const std::vector<Vec3f>& xyz, const Vec3f& viewpoint,
                                 const RunContext& context, std::size_t max_samples) {
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
  // Neighbours on slanted patches, and those of them at the sampled point's exact z.
  const double max_normal_z = std::cos(double(kTiesMinSlant) * M_PI / 180.0);
  std::size_t tie_pairs = 0, ties = 0, slanted_patches = 0;
  std::vector<std::uint32_t> nearest_distinct;
  std::vector<float> sampled_x, sampled_y;
  std::vector<float> spacing, roughness;
  std::vector<std::pair<float, float>> by_range;  // (range, roughness) of each patch
  NeighborList found;
  std::size_t seen = 0;
  for (const Vec3f& p : xyz) {
    if (!is_finite(p)) continue;
    if (seen++ % stride != 0) continue;
    context.throw_if_stopped("measuring the cloud");
    sampled_x.push_back(p.x()), sampled_y.push_back(p.y());
    search.find(p, nearest, found);
    nearest_distinct.clear();
    for (std::size_t k = 0; k < found.size(); ++k)
      if (found.sq_dists[k] > 0.0f) nearest_distinct.push_back(found.indices[k]);
    for (float sq : found.sq_dists)
      if (sq > 0.0f) {
        spacing.push_back(std::sqrt(sq));
        break;
      }
    search.find(p, patch_hood, found, false);
    if (found.size() < kRoughnessMinPoints) continue;
    const PatchFit fit = fit_patch(xyz, found);
    roughness.push_back(fit.rms);
    if (std::abs(fit.normal.z()) < max_normal_z && !nearest_distinct.empty()) {
      ++slanted_patches;
      for (std::uint32_t j : nearest_distinct) ties += xyz[j].z() == p.z() ? 1 : 0;
      tie_pairs += nearest_distinct.size();
    }
    // Sensors are noisy along the ray: the roughness across the patch is that noise times the
    // cosine of the incidence, which falls with range on a table; the growth reads it undone.
    const Eigen::Vector3d ray = fit.centre - viewpoint.cast<double>();
    const double range = ray.norm();
    const double cosine = range > 0.0 ? std::abs(fit.normal.dot(ray)) / range : 0.0;
    if (std::isfinite(range) && cosine >= kMinViewingCosine)
      by_range.emplace_back(float(range), float(fit.rms / cosine));
  }
  CloudSignature signature;
  signature.point_spacing = quantile_of(spacing, 0.5);
  signature.roughness = quantile_of(roughness, 0.5);
  signature.noise_growth = noise_growth(std::move(by_range));
  if (slanted_patches >= kTiesMinPatches &&
      !(on_a_decimal_grid(sampled_x) && on_a_decimal_grid(sampled_y)))
    signature.depth_ties = float(double(ties) / double(tie_pairs));
  return signature;
}

}  // namespace primlabel
