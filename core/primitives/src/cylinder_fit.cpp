// Cylinders: MSAC over hypotheses from two points and their normals (the axis is perpendicular to
// both normals, and both normal lines meet it), Levenberg-Marquardt on the radial residual of the
// inliers (axis, axis point, radius), then the height from the inliers' extent along the axis.

#include "fit_support.hpp"

namespace primlabel::primitives {
namespace {

using namespace detail;

struct Cylinder {
  Vec3d point = Vec3d::Zero();  // on the axis
  Vec3d axis = Vec3d::UnitZ();  // unit
  double radius = 0;

  Vec3d radial(const Vec3d& p) const {
    const Vec3d q = p - point;
    return q - q.dot(axis) * axis;
  }
  Deviation deviation(const Vec3d& p) const {
    const Vec3d r = radial(p);
    const double rho = r.norm();
    return {rho - radius, rho > 0 ? Vec3d(r / rho) : Vec3d::Zero()};
  }
};

bool within_bounds(double radius, const FitSettings& settings) {
  return radius >= settings.min_radius && radius <= settings.max_radius;
}

std::optional<Cylinder> hypothesis(const Points& pts, std::size_t i, std::size_t j,
                                   const FitSettings& settings) {
  Cylinder c;
  c.axis = pts.n[i].cross(pts.n[j]);
  if (!(c.axis.norm() > std::sin(5 * kDeg))) return std::nullopt;
  c.axis.normalize();
  // The two normal lines projected onto the plane across the axis meet on the axis.
  auto flat = [&](const Vec3d& v) { return Vec3d(v - v.dot(c.axis) * c.axis); };
  Eigen::Matrix<double, 3, 2> m;
  m << flat(pts.n[i]).normalized(), -flat(pts.n[j]).normalized();
  const Eigen::Vector2d ts = m.colPivHouseholderQr().solve(flat(pts.p[j]) - flat(pts.p[i]));
  if (!ts.allFinite()) return std::nullopt;
  c.point = flat(pts.p[i]) + ts[0] * m.col(0);
  c.radius = 0.5 * (c.radial(pts.p[i]).norm() + c.radial(pts.p[j]).norm());
  if (!within_bounds(c.radius, settings)) return std::nullopt;
  return c;
}

Cylinder refine(const Cylinder& start, const std::vector<Vec3d>& points, int iterations) {
  auto residual = [](const Cylinder& c, const Vec3d& p) { return c.radial(p).norm() - c.radius; };
  auto move = [](const Cylinder& c, const Eigen::Matrix<double, 5, 1>& d) {
    const auto [b1, b2] = frame(c.axis);
    Cylinder m = c;
    m.axis = (c.axis + d[0] * b1 + d[1] * b2).normalized();
    m.point = c.point + d[2] * b1 + d[3] * b2;
    m.radius = c.radius + d[4];
    return m;
  };
  return refine_lm<5>(start, points, residual, move, iterations);
}

// The same line either way round: the largest component positive.
Vec3d canonical_direction(const Vec3d& v) {
  Eigen::Index k;
  v.cwiseAbs().maxCoeff(&k);
  return v[k] < 0 ? Vec3d(-v) : v;
}

}  // namespace

std::optional<Fit> fit_cylinder(const SegmentPoints& points, const FitSettings& settings,
                                std::uint64_t seed) {
  const Points pts = gather(points);
  const std::size_t n = pts.with_normal.size();
  if (n < 6) return std::nullopt;
  Sampler rng(mix_seed(seed, 2));
  const std::vector<std::size_t> scoring = strided(pts.size(), settings.max_scoring_points);
  std::optional<Cylinder> best;
  double best_cost = INFINITY;
  for (int h = 0; h < settings.hypotheses; ++h) {
    const auto c =
        hypothesis(pts, pts.with_normal[rng.below(n)], pts.with_normal[rng.below(n)], settings);
    if (!c) continue;
    const double cost = msac_cost(
        pts, scoring, [&](const Vec3d& p) { return c->deviation(p); }, settings);
    if (cost < best_cost) best_cost = cost, best = c;
  }
  if (!best) return std::nullopt;
  Cylinder c = *best;
  auto deviate = [&](const Vec3d& p) { return c.deviation(p); };
  InlierSet inliers = select_inliers(pts, deviate, settings);
  for (int round = 0; round < 2 && inliers.indices.size() >= 6; ++round) {
    c = refine(c, refine_points(pts, inliers.indices, settings), settings.refine_iterations);
    inliers = select_inliers(pts, deviate, settings);
  }
  if (inliers.indices.size() < 6 || !within_bounds(c.radius, settings)) return std::nullopt;

  c.axis = canonical_direction(c.axis);
  double lo = INFINITY, hi = -INFINITY;
  for (std::size_t i : inliers.indices) {
    const double along = (pts.p[i] - c.point).dot(c.axis);
    lo = std::min(lo, along), hi = std::max(hi, along);
  }
  CylinderModel model;
  model.axis = c.axis;
  model.center = c.point + 0.5 * (lo + hi) * c.axis;
  model.radius = c.radius;
  model.height = hi - lo;
  Fit fit;
  fit.model = model;
  fit.inliers = inliers.indices.size();
  fit.rms = inliers.rms;
  const double coverage = std::min(1.0, arc_span(pts, inliers.indices, c.point, c.axis) / M_PI);
  fit.confidence = double(fit.inliers) / double(pts.size()) * coverage;
  return fit;
}

}  // namespace primlabel::primitives
