#include "primlabel/tabletop/plane_fit.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel::tabletop {

using primlabel::detail::parallel_for;
using primlabel::detail::Schedule;

void PlaneFitOptions::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (!(distance_threshold > 0.0f) || !std::isfinite(distance_threshold))
    fail("plane distance threshold must be positive, got " + std::to_string(distance_threshold));
  if (axis && (!is_finite(*axis) || axis->norm() < 1e-6f))
    fail("plane axis must be a finite non-zero vector");
  if (!(max_angle_deg > 0.0f && max_angle_deg <= 90.0f))
    fail("plane max angle must be in (0, 90] degrees, got " + std::to_string(max_angle_deg));
  if (max_iterations < 1) fail("plane max iterations must be at least 1");
  if (!(confidence > 0.0 && confidence < 1.0))
    fail("plane confidence must be in (0, 1), got " + std::to_string(confidence));
  if (max_scoring_points < 3) fail("plane max scoring points must be at least 3");
  if (refine_iterations < 0) fail("plane refine iterations must not be negative");
}

const char* to_string(PlaneFitStatus status) {
  switch (status) {
    case PlaneFitStatus::kOk:
      return "ok";
    case PlaneFitStatus::kTooFewPoints:
      return "too_few_points";
    case PlaneFitStatus::kNoPlane:
      return "no_plane";
    case PlaneFitStatus::kNotWithinAngle:
      return "not_within_angle";
  }
  return "unknown";
}

PlaneEstimate estimate_plane(const std::vector<Vec3f>& points,
                             const std::vector<std::uint32_t>& indices) {
  PlaneEstimate estimate;
  estimate.plane = Eigen::Vector4f::Constant(std::numeric_limits<float>::quiet_NaN());
  if (indices.size() < 3) return estimate;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::uint32_t i : indices) mean += points[i].cast<double>();
  mean /= double(indices.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::uint32_t i : indices) {
    const Eigen::Vector3d d = points[i].cast<double>() - mean;
    covariance.noalias() += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d normal = solver.eigenvectors().col(0).normalized();
  if (!normal.allFinite()) return estimate;
  estimate.plane << normal.cast<float>(), static_cast<float>(-normal.dot(mean));
  estimate.narrow_spread =
      std::sqrt(std::max(0.0, solver.eigenvalues()[1] / double(indices.size())));
  return estimate;
}

namespace {

// SplitMix64: a small, fully specified generator, so that a seed means the same samples with
// every standard library.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::size_t below(std::size_t n) {  // uniform in [0, n), n < 2^32
    return static_cast<std::size_t>(((next() >> 32) * std::uint64_t(n)) >> 32);
  }

 private:
  std::uint64_t state_;
};

struct Hypothesis {
  Eigen::Vector4f plane = Eigen::Vector4f::Zero();
  bool usable = false;
  double cost = 0.0;
  std::size_t inliers = 0;
};

// Plane through three points; unusable when they are (nearly) collinear.
Hypothesis plane_through(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  Hypothesis h;
  const Eigen::Vector3d ab = (b - a).cast<double>(), ac = (c - a).cast<double>();
  Eigen::Vector3d n = ab.cross(ac);
  const double area = n.norm();
  if (!(area > 1e-12 * ab.squaredNorm() + 1e-18)) return h;
  n /= area;
  h.plane << n.cast<float>(), static_cast<float>(-n.dot(a.cast<double>()));
  h.usable = true;
  return h;
}

std::vector<std::uint32_t> select_inliers(const std::vector<Vec3f>& points,
                                          const std::vector<std::uint32_t>& indices,
                                          const Eigen::Vector4f& plane, float threshold) {
  std::vector<std::uint32_t> inliers;
  inliers.reserve(indices.size());
  for (std::uint32_t i : indices)
    if (std::abs(signed_distance(plane, points[i])) <= threshold) inliers.push_back(i);
  return inliers;
}

float angle_deg(const Vec3f& normal, const Vec3f& axis) {
  const float c = std::min(1.0f, std::abs(normal.normalized().dot(axis.normalized())));
  return std::acos(c) * 180.0f / static_cast<float>(M_PI);
}

}  // namespace

PlaneFit fit_plane(const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& indices,
                   const PlaneFitOptions& options, const RunContext& context) {
  options.validate();
  PlaneFit fit;
  const std::size_t n = indices.size();
  if (n < 3 || n < options.min_inliers) {
    fit.status = PlaneFitStatus::kTooFewPoints;
    fit.message = "only " + std::to_string(n) + " valid points, need at least " +
                  std::to_string(std::max<std::size_t>(3, options.min_inliers)) + " for a plane";
    return fit;
  }
  const std::optional<Vec3f> axis =
      options.axis ? std::optional<Vec3f>(options.axis->normalized()) : std::nullopt;
  const float min_cos = std::cos(options.max_angle_deg * static_cast<float>(M_PI) / 180.0f);

  // Hypotheses are scored on an evenly strided subset: cheap, and spread over the whole scan.
  const std::size_t scored = std::min(n, options.max_scoring_points);
  std::vector<Vec3f> subset(scored);
  for (std::size_t k = 0; k < scored; ++k) subset[k] = points[indices[k * n / scored]];
  const float t = options.distance_threshold;
  const double sq_t = double(t) * t;
  // The subset's share of min_inliers, so small planes are not accepted on the subset alone.
  const double min_subset_inliers = double(options.min_inliers) * double(scored) / double(n);

  Random random(options.seed);
  constexpr int kBlock = 32;  // hypotheses per parallel round; fixed, so results ignore threads
  const int threads = primlabel::detail::resolve_threads(context.threads);
  Hypothesis best;
  best.cost = std::numeric_limits<double>::infinity();
  double needed = options.max_iterations;
  int drawn = 0;
  std::vector<Hypothesis> block;
  while (drawn < needed && drawn < options.max_iterations) {
    context.throw_if_stopped("fitting the table plane");
    const int count = std::min<int>(kBlock, options.max_iterations - drawn);
    block.assign(count, Hypothesis{});
    for (int h = 0; h < count; ++h) {
      std::size_t a = random.below(n), b = random.below(n), c = random.below(n);
      if (a == b || a == c || b == c) continue;
      block[h] = plane_through(points[indices[a]], points[indices[b]], points[indices[c]]);
      if (block[h].usable && axis && std::abs(block[h].plane.head<3>().dot(*axis)) < min_cos)
        block[h].usable = false;  // outside the allowed tilt: not even scored
    }
    parallel_for(count, threads, Schedule::Dynamic(1), [&](std::ptrdiff_t h) {
      Hypothesis& hyp = block[h];
      if (!hyp.usable) return;
      double cost = 0.0;
      std::size_t inliers = 0;
      for (const Vec3f& p : subset) {
        const double d = signed_distance(hyp.plane, p);
        const double sq = d * d;
        if (sq <= sq_t) {
          cost += sq;
          ++inliers;
        } else {
          cost += sq_t;
        }
      }
      hyp.cost = cost;
      hyp.inliers = inliers;
    });
    for (const Hypothesis& hyp : block)
      if (hyp.usable && hyp.cost < best.cost) best = hyp;
    drawn += count;
    if (best.usable && best.inliers > 0) {
      const double w = double(best.inliers) / double(scored);
      const double miss = 1.0 - w * w * w;
      needed = miss <= 0.0 ? 0.0 : std::log(1.0 - options.confidence) / std::log(miss);
    }
  }
  fit.iterations = drawn;

  const auto no_plane = [&] {
    if (axis) {  // Is there a plane at all, just not within the angle? Say how far off it is.
      PlaneFitOptions free = options;
      free.axis.reset();
      const PlaneFit unconstrained = fit_plane(points, indices, free, context);
      if (unconstrained.status == PlaneFitStatus::kOk) {
        fit.status = PlaneFitStatus::kNotWithinAngle;
        fit.rejected_plane = unconstrained.plane;
        fit.angle_to_axis_deg = angle_deg(unconstrained.plane.head<3>(), *axis);
        char text[200];
        std::snprintf(text, sizeof text,
                      "no plane within %.1f deg of the up axis; the dominant plane (%zu points) is "
                      "%.1f deg off",
                      options.max_angle_deg, unconstrained.inliers.size(), fit.angle_to_axis_deg);
        fit.message = text;
        return fit;
      }
    }
    fit.status = PlaneFitStatus::kNoPlane;
    fit.message = "no plane with at least " + std::to_string(options.min_inliers) +
                  " points within " + std::to_string(t) + " m";
    return fit;
  };
  if (!best.usable || double(best.inliers) < min_subset_inliers) return no_plane();

  // Least-squares refinement: refit on the inliers of all points, reselect, until stable.
  Eigen::Vector4f plane = best.plane;
  std::vector<std::uint32_t> inliers = select_inliers(points, indices, plane, t);
  for (int round = 0; round < options.refine_iterations; ++round) {
    const Eigen::Vector4f refined = estimate_plane(points, inliers).plane;
    if (!refined.allFinite()) break;
    std::vector<std::uint32_t> reselected = select_inliers(points, indices, refined, t);
    if (reselected.size() < inliers.size()) break;  // refinement made it worse: keep the last
    plane = refined;
    const bool stable = reselected == inliers;
    inliers = std::move(reselected);
    if (stable) break;
  }
  if (inliers.size() < options.min_inliers) return no_plane();
  // A band slicing through a larger surface at an angle is a strip, not a plane: its inliers
  // barely extend across the strip. Demand a real two-dimensional patch.
  if (estimate_plane(points, inliers).narrow_spread < 2.0 * t) return no_plane();
  if (axis) {
    if (plane.head<3>().dot(*axis) < 0.0f) plane = -plane;
    fit.angle_to_axis_deg = angle_deg(plane.head<3>(), *axis);
    if (fit.angle_to_axis_deg > options.max_angle_deg) return no_plane();
  }
  fit.status = PlaneFitStatus::kOk;
  fit.plane = plane;
  fit.inliers = std::move(inliers);
  return fit;
}

}  // namespace primlabel::tabletop
