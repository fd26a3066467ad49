#pragma once
// What every model's fit shares: the segment's points in double precision, the seeded sampler,
// strided subsets, MSAC scoring, inlier selection and a Levenberg-Marquardt refinement with a
// numeric Jacobian (a handful of parameters, so forward differences are cheap and exact enough).

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "primlabel/primitives/fitters.hpp"

namespace primlabel::primitives::detail {

constexpr double kDeg = M_PI / 180.0;

// SplitMix64: the same sequence on every platform (std:: distributions differ between libraries).
class Sampler {
 public:
  explicit Sampler(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, n), n > 0.
  std::size_t below(std::size_t n) {
    return static_cast<std::size_t>((double(next() >> 11) * 0x1.0p-53) * double(n));
  }

 private:
  std::uint64_t state_;
};

// A seed of its own for stream `stream` (a model, a segment) of `seed`.
inline std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream) {
  Sampler s(seed ^ (stream + 0x632BE59BD9B4E019ull) * 0xBF58476D1CE4E5B9ull);
  return s.next();
}

// The finite points of a segment; n[i] is NaN where the point has no (finite) normal, else unit.
struct Points {
  std::vector<Vec3d> p, n;
  std::vector<std::size_t> with_normal;  // indices of points with a normal
  std::size_t size() const { return p.size(); }
  bool has_normal(std::size_t i) const { return std::isfinite(n[i].x()); }
};
Points gather(const SegmentPoints& points);

// At most `max` of 0..n-1 (or of `from`), evenly strided, in order.
std::vector<std::size_t> strided(std::size_t n, std::size_t max);
std::vector<std::size_t> strided(const std::vector<std::size_t>& from, std::size_t max);

// What scores a point against a model: its signed distance to the surface and the surface's unit
// normal at the nearest point.
struct Deviation {
  double distance = INFINITY;
  Vec3d normal = Vec3d::Zero();
};

// Normal agreement either way round: estimated normals face the sensor, and concave surfaces
// (the inside of a mug) have them facing the axis.
inline bool agrees(const Points& pts, std::size_t i, const Vec3d& surface_normal, double min_cos) {
  return !pts.has_normal(i) || std::abs(pts.n[i].dot(surface_normal)) >= min_cos;
}

// Mean truncated quadratic cost (MSAC) over `subset`: d^2 / t^2 for an inlier, 1 otherwise.
template <class Deviate>
double msac_cost(const Points& pts, const std::vector<std::size_t>& subset, Deviate&& deviate,
                 const FitSettings& settings) {
  const double t2 = settings.distance_threshold * settings.distance_threshold;
  const double min_cos = std::cos(settings.normal_angle_deg * kDeg);
  double cost = 0;
  for (std::size_t i : subset) {
    const Deviation d = deviate(pts.p[i]);
    const double d2 = d.distance * d.distance;
    cost += (d2 < t2 && agrees(pts, i, d.normal, min_cos)) ? d2 / t2 : 1.0;
  }
  return subset.empty() ? 1.0 : cost / double(subset.size());
}

struct InlierSet {
  std::vector<std::size_t> indices;
  double rms = 0;
};

template <class Deviate>
InlierSet select_inliers(const Points& pts, Deviate&& deviate, const FitSettings& settings) {
  const double t = settings.distance_threshold;
  const double min_cos = std::cos(settings.normal_angle_deg * kDeg);
  InlierSet out;
  double squares = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Deviation d = deviate(pts.p[i]);
    if (std::abs(d.distance) < t && agrees(pts, i, d.normal, min_cos)) {
      out.indices.push_back(i);
      squares += d.distance * d.distance;
    }
  }
  out.rms = out.indices.empty() ? 0.0 : std::sqrt(squares / double(out.indices.size()));
  return out;
}

// Levenberg-Marquardt on sum residual(model, p)^2 over `points`; move(model, delta) applies an
// N-parameter step in the model's local coordinates. Steps that do not lower the cost are
// refused (the damping grows), so the result is never worse than the start.
template <int N, class M, class Residual, class Move>
M refine_lm(M model, const std::vector<Vec3d>& points, Residual&& residual, Move&& move,
            int iterations) {
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  if (points.size() < std::size_t(N)) return model;
  auto cost = [&](const M& m) {
    double s = 0;
    for (const Vec3d& p : points) {
      const double r = residual(m, p);
      s += r * r;
    }
    return s;
  };
  double current = cost(model);
  if (!std::isfinite(current)) return model;
  double lambda = 1e-3;
  constexpr double h = 1e-7;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    M probes[N];
    for (int k = 0; k < N; ++k) probes[k] = move(model, Vec::Unit(k) * h);
    Mat jtj = Mat::Zero();
    Vec jtr = Vec::Zero();
    for (const Vec3d& p : points) {
      const double r = residual(model, p);
      Vec j;
      for (int k = 0; k < N; ++k) j[k] = (residual(probes[k], p) - r) / h;
      jtj += j * j.transpose();
      jtr += j * r;
    }
    bool accepted = false;
    double step_norm = 0;
    for (int attempt = 0; attempt < 8 && !accepted; ++attempt) {
      Mat damped = jtj;
      for (int k = 0; k < N; ++k) damped(k, k) += lambda * (jtj(k, k) + 1e-12);
      const Vec step = damped.ldlt().solve(-jtr);
      if (!step.allFinite()) return model;
      const M candidate = move(model, step);
      const double c = cost(candidate);
      if (std::isfinite(c) && c < current) {
        model = candidate;
        accepted = true;
        step_norm = step.norm();
        current = c;
        lambda = std::max(lambda * 0.1, 1e-9);
      } else {
        lambda *= 10;
      }
    }
    if (!accepted || step_norm < 1e-10) break;
  }
  return model;
}

// The points at `indices` (at most max_refine_points of them, strided).
std::vector<Vec3d> refine_points(const Points& pts, const std::vector<std::size_t>& indices,
                                 const FitSettings& settings);

// Two unit vectors completing `axis` to an orthonormal frame.
inline std::pair<Vec3d, Vec3d> frame(const Vec3d& axis) {
  const Vec3d u = axis.unitOrthogonal();
  return {u, axis.cross(u)};
}

// Angle (radians) the points span around `axis` through `center`: 2 pi less the widest run of
// empty 5 degree sectors.
double arc_span(const Points& pts, const std::vector<std::size_t>& indices, const Vec3d& center,
                const Vec3d& axis);
// Half-angle (radians) of the cap of directions from `center` the points cover (95th
// percentile around their mean direction; pi when they surround it).
double cap_half_angle(const Points& pts, const std::vector<std::size_t>& indices,
                      const Vec3d& center);

// Least-squares plane through pts.p[indices] (double accumulation, fixed order): unit normal and
// centroid; the normal is NaN for fewer than three points.
struct PlaneEstimate {
  Vec3d normal = Vec3d::Constant(NAN), centroid = Vec3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: principal axes, largest first
};
PlaneEstimate estimate_plane(const Points& pts, const std::vector<std::size_t>& indices);

}  // namespace primlabel::primitives::detail

namespace primlabel::primitives::detail {

// MSAC plane over pts.p[candidates] then least-squares refits (plane_fit.cpp); inliers are
// among `candidates`. Nothing for fewer than three candidates or only collinear samples.
struct PlaneHypothesis {
  Vec3d normal = Vec3d::UnitZ();
  double offset = 0;
  InlierSet inliers;
};
std::optional<PlaneHypothesis> msac_plane(const Points& pts,
                                          const std::vector<std::size_t>& candidates,
                                          const FitSettings& settings, Sampler& rng);

}  // namespace primlabel::primitives::detail
