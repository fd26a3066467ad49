// The cylinder model of a segment: MSAC over axis hypotheses from two points and their normals
// (the axis is perpendicular to both normals, and both normal lines meet it), Gauss-Newton least
// squares on the inliers, then upright or lying: the axis snapped to the table normal or into the
// table plane, the circle refitted, the foot on the table when the points reach it.

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>

#include "primlabel/synth/random.hpp"
#include "shape_fit.hpp"

namespace primlabel::synth::fit {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kMinRadius = 0.01, kMaxRadius = 0.25;
const double kNormalAgrees = std::cos(45 * kDeg);
const double kCapNormal = std::cos(30 * kDeg);
// The side must be seen over this much of its circumference (a can in view shows 90-180°).
constexpr double kMinArc = 45 * kDeg;

struct Cylinder {
  Vec3d axis = Vec3d::UnitZ();  // unit
  Vec3d point = Vec3d::Zero();  // on the axis
  double radius = 0;

  Vec3d radial(const Vec3d& p) const {
    const Vec3d q = p - point;
    return q - q.dot(axis) * axis;
  }
  double residual(const Vec3d& p) const { return radial(p).norm() - radius; }
};

// Inlier of the side: within the bound of it, and its normal (if any) pointing away from the axis.
bool side_inlier(const Cylinder& c, const SegmentPoints& s, std::size_t i) {
  const Vec3d r = c.radial(s.p[i]);
  if (std::abs(r.norm() - c.radius) >= s.bound[i]) return false;
  return !std::isfinite(s.n[i].x()) || s.n[i].dot(r.normalized()) > kNormalAgrees;
}

// Extent along the axis of the points within the bound of the solid's radius (side and caps);
// a cap seen by enough points sits at their least-squares (mean) offset, as a box face does.
std::optional<std::pair<double, double>> extent(const Cylinder& c, const SegmentPoints& s,
                                                const std::vector<std::size_t>& idx) {
  std::vector<double> along;
  for (std::size_t i : idx)
    if (c.radial(s.p[i]).norm() < c.radius + s.bound[i]) along.push_back(c.axis.dot(s.p[i]));
  if (along.size() < 10) return std::nullopt;
  // quantile()'s 0.5% and 99.5% order statistics from one copy: the upper one lies past the lower.
  const std::size_t last = along.size() - 1;
  const auto rank = [&](double q) { return std::min(last, std::size_t(q * double(last) + 0.5)); };
  const auto lower = along.begin() + std::ptrdiff_t(rank(0.005));
  std::nth_element(along.begin(), lower, along.end());
  const auto upper = along.begin() + std::ptrdiff_t(rank(0.995));
  std::nth_element(lower + 1, upper, along.end());
  double ends[2] = {*lower, *upper};
  for (double& end : ends) {
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t i : idx) {
      const double a = c.axis.dot(s.p[i]);
      if (std::abs(a - end) < 2 * s.bound[i] && std::abs(s.n[i].dot(c.axis)) > kCapNormal &&
          c.radial(s.p[i]).norm() < c.radius + s.bound[i])
        sum += a, ++n;
    }
    if (n >= 20) end = sum / double(n);
  }
  return std::pair{ends[0], ends[1]};
}

// Mean truncated cost of the closed cylinder (side and both caps at the points' extent), so a
// hypothesis is judged on the whole object, a can's lid included. Infinite once the mean cannot
// come below `beaten` (the best so far): the terms are never negative.
double msac_cost(const Cylinder& c, const SegmentPoints& s, const std::vector<std::size_t>& idx,
                 double beaten = INFINITY) {
  const auto range = extent(c, s, idx);
  if (!range) return INFINITY;
  const auto [lo, hi] = *range;
  // A margin over the bound, so that rounding of the mean can never lose the hypothesis that wins.
  const double give_up = beaten * double(idx.size()) * (1 + 1e-9);
  double cost = 0;
  for (std::size_t i : idx) {
    if (cost > give_up) return INFINITY;
    const double t2 = s.bound[i] * s.bound[i];
    const double rho = c.radial(s.p[i]).norm(), along = c.axis.dot(s.p[i]);
    const double side = std::hypot(rho - c.radius, std::max({lo - along, along - hi, 0.0}));
    const double cap_rho = std::max(rho - c.radius, 0.0);
    const bool top = std::abs(along - hi) < std::abs(along - lo);
    const double cap = std::hypot(std::abs(along - (top ? hi : lo)), cap_rho);
    const double d = std::min(side, cap);
    const Vec3d normal =
        side <= cap ? Vec3d(c.radial(s.p[i]).normalized()) : Vec3d(top ? c.axis : Vec3d(-c.axis));
    cost += supports(d, s.bound[i], s.n[i], normal) ? d * d / t2 : 1.0;
  }
  return cost / double(idx.size());
}

// Upright (within 15 degrees of the table normal) or lying (within 15 of the table plane): the
// only poses a cylinder of a table scene takes here.
bool upright_or_lying(const Cylinder& c) {
  const double tilt = std::acos(std::min(1.0, std::abs(c.axis.z()))) / kDeg;
  return tilt < 15 || tilt > 75;
}

std::optional<Cylinder> hypothesis(const SegmentPoints& s, std::size_t i, std::size_t j) {
  Cylinder c;
  c.axis = s.n[i].cross(s.n[j]);
  if (c.axis.norm() < std::sin(10 * kDeg)) return std::nullopt;
  c.axis.normalize();
  // The two normal lines projected onto the plane across the axis meet on the axis.
  auto flat = [&](const Vec3d& v) { return Vec3d(v - v.dot(c.axis) * c.axis); };
  Eigen::Matrix<double, 3, 2> m;
  m << flat(s.n[i]).normalized(), -flat(s.n[j]).normalized();
  const Eigen::Vector2d ts = m.colPivHouseholderQr().solve(flat(s.p[j]) - flat(s.p[i]));
  c.point = flat(s.p[i]) + ts[0] * m.col(0);
  c.radius = 0.5 * (c.radial(s.p[i]).norm() + c.radial(s.p[j]).norm());
  if (!(c.radius > kMinRadius && c.radius < kMaxRadius)) return std::nullopt;
  return c;
}

// Gauss-Newton on the geometric residual with a numeric Jacobian. `free_axis` false keeps the
// axis direction (the circle only).
Cylinder refine(Cylinder c, const SegmentPoints& s, const std::vector<std::size_t>& idx,
                bool free_axis) {
  if (idx.size() < 6) return c;
  for (int iteration = 0; iteration < 8; ++iteration) {
    const Vec3d b1 = c.axis.unitOrthogonal(), b2 = c.axis.cross(b1);
    auto moved = [&](const Eigen::Matrix<double, 5, 1>& d) {
      Cylinder m = c;
      if (free_axis) m.axis = (c.axis + d[0] * b1 + d[1] * b2).normalized();
      m.point = c.point + d[2] * b1 + d[3] * b2;
      m.radius = c.radius + d[4];
      return m;
    };
    Eigen::Matrix<double, 5, 5> jtj = Eigen::Matrix<double, 5, 5>::Zero();
    Eigen::Matrix<double, 5, 1> jtr = Eigen::Matrix<double, 5, 1>::Zero();
    constexpr double h = 1e-6;
    std::array<Cylinder, 5> probes;
    for (int k = 0; k < 5; ++k) {
      Eigen::Matrix<double, 5, 1> d = Eigen::Matrix<double, 5, 1>::Zero();
      d[k] = h;
      probes[k] = moved(d);
    }
    for (std::size_t i : idx) {
      const double r = c.residual(s.p[i]);
      Eigen::Matrix<double, 5, 1> j;
      for (int k = 0; k < 5; ++k) j[k] = (probes[k].residual(s.p[i]) - r) / h;
      if (!free_axis) j[0] = j[1] = 0;
      jtj += j * j.transpose();
      jtr += j * r;
    }
    if (!free_axis) jtj(0, 0) = jtj(1, 1) = 1;
    const Eigen::Matrix<double, 5, 1> step = jtj.ldlt().solve(-jtr);
    if (!step.allFinite()) break;
    c = moved(step);
    if (step.norm() < 1e-7) break;
  }
  return c;
}

// Angle the side inliers span around the axis (2π less the widest empty sector). A narrow arc
// of a wide cylinder is as flat as a plane within the noise: no evidence of curvature.
double arc_span(const Cylinder& c, const SegmentPoints& s, const std::vector<std::size_t>& idx) {
  if (idx.size() < 2) return 0;
  const Vec3d u = c.axis.unitOrthogonal(), v = c.axis.cross(u);
  std::vector<double> angles;
  for (std::size_t i : idx) {
    const Vec3d r = c.radial(s.p[i]);
    angles.push_back(std::atan2(r.dot(v), r.dot(u)));
  }
  std::sort(angles.begin(), angles.end());
  double gap = angles.front() + 2 * M_PI - angles.back();
  for (std::size_t k = 1; k < angles.size(); ++k) gap = std::max(gap, angles[k] - angles[k - 1]);
  return 2 * M_PI - gap;
}

std::vector<std::size_t> inliers(const Cylinder& c, const SegmentPoints& s) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < s.p.size(); ++i)
    if (side_inlier(c, s, i)) out.push_back(i);
  return out;
}

}  // namespace

std::optional<FittedObject> fit_cylinder(const SegmentPoints& s, const FitSettings& settings) {
  std::vector<std::size_t> with_normal;
  for (std::size_t i = 0; i < s.p.size(); ++i)
    if (std::isfinite(s.n[i].x())) with_normal.push_back(i);
  if (with_normal.size() < 30) return std::nullopt;
  // Hypotheses are scored on an evenly spread subset, as the plane fit does.
  std::vector<std::size_t> scoring;
  const std::size_t stride = std::max<std::size_t>(1, with_normal.size() / 2000);
  for (std::size_t k = 0; k < with_normal.size(); k += stride) scoring.push_back(with_normal[k]);

  synth::Rng rng(synth::mix_seed(settings.seed, 77));
  std::optional<Cylinder> best;
  double best_cost = INFINITY;
  const int n = static_cast<int>(with_normal.size());
  for (int it = 0; it < 400; ++it) {
    const auto c = hypothesis(s, with_normal[rng.below(n)], with_normal[rng.below(n)]);
    if (!c || !upright_or_lying(*c)) continue;
    const double cost = msac_cost(*c, s, scoring, best_cost);
    if (cost < best_cost) best_cost = cost, best = c;
  }
  if (!best) return std::nullopt;
  Cylinder c = refine(*best, s, inliers(*best, s), true);
  const Vec3d up = Vec3d::UnitZ();
  const double tilt = std::acos(std::min(1.0, std::abs(c.axis.dot(up)))) / kDeg;
  FittedObject out;
  if (tilt < 15) {
    out.kind = FittedKind::kUprightCylinder;
    c.axis = up;
  } else if (tilt > 75) {
    out.kind = FittedKind::kLyingCylinder;
    c.axis = Vec3d(c.axis.x(), c.axis.y(), 0).normalized();
  } else {
    return std::nullopt;
  }
  c.point -= c.point.dot(c.axis) * c.axis;
  c = refine(c, s, inliers(c, s), false);
  if (!(c.radius > kMinRadius && c.radius < kMaxRadius)) return std::nullopt;
  if (arc_span(c, s, inliers(c, s)) < kMinArc) return std::nullopt;

  std::vector<std::size_t> all(s.p.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  const auto range = extent(c, s, all);
  if (!range) return std::nullopt;
  auto [lo, hi] = *range;
  out.size = Vec3d(c.radius, 0, 0);
  out.table_from_local = Eigen::Isometry3d::Identity();
  if (out.kind == FittedKind::kUprightCylinder) {
    out.on_table = lo < settings.contact_tolerance;
    if (out.on_table) lo = 0;
    out.size.y() = std::max(hi - lo, 0.005);
    out.table_from_local.translation() = Vec3d(c.point.x(), c.point.y(), lo);
  } else {
    const Vec3d y = up.cross(c.axis);
    out.size.y() = std::max(hi - lo, 0.005);
    double bottom = c.point.z() - c.radius;  // the lowest line of the side
    out.on_table = std::abs(bottom) < settings.contact_tolerance;
    if (out.on_table) bottom = 0;
    Eigen::Matrix3d axes;
    axes << c.axis, y, up;
    out.table_from_local.linear() = axes;
    const Vec3d centre = c.point + 0.5 * (lo + hi) * c.axis;
    out.table_from_local.translation() = Vec3d(centre.x(), centre.y(), bottom);
  }
  return out;
}

}  // namespace primlabel::synth::fit
