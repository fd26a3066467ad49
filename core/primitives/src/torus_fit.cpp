// Tori: every normal line of a surface of revolution meets its axis, a linear condition on the
// axis' Plücker coordinates (a, a_bar = c x a): a . (p x n) + a_bar . n = 0 (Pottmann & Wallner).
// MSAC draws eight points with normals, takes the axis from that 6x6 least-squares problem, the
// tube's centre circle from where the normal lines cross in the meridian plane, and scores the
// torus; Levenberg-Marquardt refines all seven parameters on the inliers.

#include <Eigen/Eigenvalues>

#include "fit_support.hpp"

namespace primlabel::primitives {
namespace {

using namespace detail;

constexpr int kSample = 8;

struct Torus {
  Vec3d center = Vec3d::Zero();
  Vec3d axis = Vec3d::UnitZ();
  double major = 0, minor = 0;

  Deviation deviation(const Vec3d& p) const {
    const Vec3d q = p - center;
    const double z = q.dot(axis);
    const Vec3d radial = q - z * axis;
    const double rho = radial.norm();
    const Vec3d u = rho > 0 ? Vec3d(radial / rho) : axis.unitOrthogonal();
    const Vec3d tube = (rho - major) * u + z * axis;  // from the tube's centre circle
    const double d = tube.norm();
    return {d - minor, d > 0 ? Vec3d(tube / d) : Vec3d::Zero()};
  }
};

// Axis and tube circle from the sampled points (coordinates relative to `origin`, for
// conditioning).
std::optional<Torus> hypothesis(const Points& pts, const std::size_t (&k)[kSample],
                                const Vec3d& origin, const FitSettings& settings) {
  Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Zero();
  for (std::size_t i : k) {
    Eigen::Matrix<double, 6, 1> row;
    row << (pts.p[i] - origin).cross(pts.n[i]), pts.n[i];
    m += row * row.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> solver(m);
  if (solver.info() != Eigen::Success) return std::nullopt;
  const Eigen::Matrix<double, 6, 1> x = solver.eigenvectors().col(0);
  const double scale = x.head<3>().norm();
  if (!(scale > 1e-6)) return std::nullopt;
  Torus t;
  t.axis = x.head<3>() / scale;
  const Vec3d moment = x.tail<3>() / scale;
  const Vec3d on_axis = origin + t.axis.cross(moment);
  // In the meridian plane (rho, z) each normal line passes through the tube's centre.
  Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  Eigen::Vector2d q[kSample];
  for (int s = 0; s < kSample; ++s) {
    const Vec3d rel = pts.p[k[s]] - on_axis;
    const double z = rel.dot(t.axis);
    const Vec3d radial = rel - z * t.axis;
    const double rho = radial.norm();
    if (!(rho > 0)) return std::nullopt;
    const Vec3d& n = pts.n[k[s]];
    q[s] = Eigen::Vector2d(rho, z);
    const Eigen::Vector2d dir(n.dot(radial / rho), n.dot(t.axis));
    if (!(dir.norm() > 1e-6)) return std::nullopt;
    const Eigen::Vector2d e(-dir.y() / dir.norm(), dir.x() / dir.norm());
    a += e * e.transpose();
    b += e * e.dot(q[s]);
  }
  if (std::abs(a.determinant()) < 1e-6) return std::nullopt;  // all normals alike
  const Eigen::Vector2d tube = a.ldlt().solve(b);
  double minor = 0;
  for (const auto& point : q) minor += (point - tube).norm();
  t.major = tube.x();
  t.minor = minor / kSample;
  t.center = on_axis + tube.y() * t.axis;
  if (!(t.major >= settings.min_radius && t.major <= settings.max_radius && t.minor > 0 &&
        t.minor <= settings.max_radius))
    return std::nullopt;
  return t;
}

Torus refine(const Torus& start, const std::vector<Vec3d>& points, int iterations) {
  auto residual = [](const Torus& t, const Vec3d& p) { return t.deviation(p).distance; };
  auto move = [](const Torus& t, const Eigen::Matrix<double, 7, 1>& d) {
    const auto [b1, b2] = frame(t.axis);
    Torus m = t;
    m.axis = (t.axis + d[0] * b1 + d[1] * b2).normalized();
    m.center = t.center + d.segment<3>(2);
    m.major = t.major + d[5];
    m.minor = t.minor + d[6];
    return m;
  };
  return refine_lm<7>(start, points, residual, move, iterations);
}

}  // namespace

std::optional<Fit> fit_torus(const SegmentPoints& points, const FitSettings& settings,
                             std::uint64_t seed) {
  const Points pts = gather(points);
  const std::size_t n = pts.with_normal.size();
  if (n < 2 * kSample) return std::nullopt;
  Vec3d origin = Vec3d::Zero();
  for (const Vec3d& p : pts.p) origin += p;
  origin /= double(pts.size());
  Sampler rng(mix_seed(seed, 4));
  const std::vector<std::size_t> scoring = strided(pts.size(), settings.max_scoring_points);
  std::optional<Torus> best;
  double best_cost = INFINITY;
  for (int h = 0; h < settings.hypotheses; ++h) {
    std::size_t k[kSample];
    for (auto& i : k) i = pts.with_normal[rng.below(n)];
    const auto t = hypothesis(pts, k, origin, settings);
    if (!t) continue;
    const double cost = msac_cost(
        pts, scoring, [&](const Vec3d& p) { return t->deviation(p); }, settings);
    if (cost < best_cost) best_cost = cost, best = t;
  }
  if (!best) return std::nullopt;
  Torus t = *best;
  auto deviate = [&](const Vec3d& p) { return t.deviation(p); };
  InlierSet inliers = select_inliers(pts, deviate, settings);
  for (int round = 0; round < 2 && inliers.indices.size() >= 7; ++round) {
    t = refine(t, refine_points(pts, inliers.indices, settings), settings.refine_iterations);
    inliers = select_inliers(pts, deviate, settings);
  }
  if (inliers.indices.size() < 7 || !(t.major >= settings.min_radius) ||
      !(t.major <= settings.max_radius) || !(t.minor > 0))
    return std::nullopt;
  // The same axis either way round: the largest component positive.
  Eigen::Index largest;
  t.axis.cwiseAbs().maxCoeff(&largest);
  if (t.axis[largest] < 0) t.axis = -t.axis;
  Fit fit;
  fit.model = TorusModel{t.center, t.axis, t.major, t.minor};
  fit.inliers = inliers.indices.size();
  fit.rms = inliers.rms;
  const double coverage = std::min(1.0, arc_span(pts, inliers.indices, t.center, t.axis) / M_PI);
  fit.confidence = double(fit.inliers) / double(pts.size()) * coverage;
  return fit;
}

}  // namespace primlabel::primitives
