#pragma once
// Robust plane fit: MSAC (RANSAC with truncated quadratic cost, Torr & Zisserman) over seeded
// three-point hypotheses, optionally restricted to planes whose normal lies within an angle of a
// given axis (as PCL's SACMODEL_PERPENDICULAR_PLANE), then refined by least squares on the
// inliers. Deterministic for a fixed seed and any thread count.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::tabletop {

struct PlaneFitOptions {
  float distance_threshold = 0.01f;        // inlier band half-width (m)
  std::optional<Vec3f> axis;               // when set, only planes with normal within max_angle_deg
  float max_angle_deg = 15.0f;             //   of it are accepted
  int max_iterations = 1000;               // hypotheses at most
  double confidence = 0.999;               // adaptive stop: P(an all-inlier sample was drawn)
  std::size_t max_scoring_points = 20000;  // hypotheses are scored on a fixed random subset
  std::size_t min_inliers = 100;           // fewer inliers than this is "no plane"
  int refine_iterations = 5;               // least-squares refit / re-select rounds
  std::uint64_t seed = 1;

  void validate() const;  // throws std::invalid_argument naming the bad option
};

enum class PlaneFitStatus {
  kOk,
  kTooFewPoints,    // fewer than three usable points (or fewer than min_inliers)
  kNoPlane,         // no plane with min_inliers support at all
  kNotWithinAngle,  // planes exist, but none within max_angle_deg of the axis
};

const char* to_string(PlaneFitStatus status);

struct PlaneFit {
  PlaneFitStatus status = PlaneFitStatus::kNoPlane;
  std::string message;                              // why, when status != kOk
  Eigen::Vector4f plane = Eigen::Vector4f::Zero();  // n.x n.y n.z d, |n| = 1, n.p + d = 0;
                                                    // n points along the axis when one is given
  std::vector<std::uint32_t> inliers;               // ascending indices into the points
  float angle_to_axis_deg = 0.0f;  // angle of the normal to the axis (0 without axis)
  int iterations = 0;              // hypotheses drawn
  // For kNotWithinAngle: the best unconstrained plane, to say how far off it is.
  std::optional<Eigen::Vector4f> rejected_plane;
};

// Fits a plane to points[indices] (all finite). Data conditions give a status, never a throw;
// invalid options throw std::invalid_argument. context.stop is checked per round of hypotheses
// (fit_plane then throws Cancelled); the fit does not depend on context.threads.
PlaneFit fit_plane(const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& indices,
                   const PlaneFitOptions& options, const RunContext& context = {});

struct PlaneEstimate {
  Eigen::Vector4f plane;       // NaN for fewer than three points
  double narrow_spread = 0.0;  // standard deviation along the patch's narrower in-plane axis
};

// Least-squares plane (smallest-eigenvalue eigenvector of the covariance, accumulated in double in
// a fixed order) through points[indices]. narrow_spread tells a two-dimensional patch from a
// strip where a plane slices through another surface.
PlaneEstimate estimate_plane(const std::vector<Vec3f>& points,
                             const std::vector<std::uint32_t>& indices);

inline float signed_distance(const Eigen::Vector4f& plane, const Vec3f& p) {
  return plane.head<3>().dot(p) + plane[3];
}

}  // namespace primlabel::tabletop
