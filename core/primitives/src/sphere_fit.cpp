// Spheres: MSAC over hypotheses from two points and their normals (the centre lies on both
// normal lines; four points without normals), Levenberg-Marquardt on |p - c| - r.

#include "fit_support.hpp"

namespace primlabel::primitives {
namespace {

using namespace detail;

struct Sphere {
  Vec3d center = Vec3d::Zero();
  double radius = 0;
  Deviation deviation(const Vec3d& p) const {
    const Vec3d q = p - center;
    const double d = q.norm();
    return {d - radius, d > 0 ? Vec3d(q / d) : Vec3d::Zero()};
  }
};

bool within_bounds(double radius, const FitSettings& settings) {
  return radius >= settings.min_radius && radius <= settings.max_radius;
}

// The centre halfway between the closest points of the two normal lines.
std::optional<Sphere> from_normals(const Points& pts, std::size_t i, std::size_t j) {
  const Vec3d &a = pts.p[i], &b = pts.p[j], &u = pts.n[i], &v = pts.n[j];
  const double uv = u.dot(v), denominator = 1 - uv * uv;
  if (!(denominator > std::pow(std::sin(5 * kDeg), 2))) return std::nullopt;
  const Vec3d w = a - b;
  const double s = (uv * v.dot(w) - u.dot(w)) / denominator;
  const double t = (v.dot(w) - uv * u.dot(w)) / denominator;
  Sphere sphere;
  sphere.center = 0.5 * ((a + s * u) + (b + t * v));
  sphere.radius = 0.5 * ((a - sphere.center).norm() + (b - sphere.center).norm());
  return sphere;
}

// x^2 + y^2 + z^2 + D x + E y + F z + G = 0 through four points.
std::optional<Sphere> from_four(const Points& pts, const std::size_t (&k)[4]) {
  Eigen::Matrix4d m;
  Eigen::Vector4d rhs;
  for (int r = 0; r < 4; ++r) {
    const Vec3d& p = pts.p[k[r]];
    m.row(r) << p.x(), p.y(), p.z(), 1;
    rhs[r] = -p.squaredNorm();
  }
  Eigen::FullPivLU<Eigen::Matrix4d> lu(m);
  if (!lu.isInvertible()) return std::nullopt;
  const Eigen::Vector4d x = lu.solve(rhs);
  Sphere sphere;
  sphere.center = -0.5 * x.head<3>();
  const double r2 = sphere.center.squaredNorm() - x[3];
  if (!(r2 > 0)) return std::nullopt;
  sphere.radius = std::sqrt(r2);
  return sphere;
}

}  // namespace

std::optional<Fit> fit_sphere(const SegmentPoints& points, const FitSettings& settings,
                              std::uint64_t seed) {
  const Points pts = gather(points);
  if (pts.size() < 4) return std::nullopt;
  const bool use_normals = pts.with_normal.size() >= 4;
  Sampler rng(mix_seed(seed, 3));
  const std::vector<std::size_t> scoring = strided(pts.size(), settings.max_scoring_points);
  std::optional<Sphere> best;
  double best_cost = INFINITY;
  for (int h = 0; h < settings.hypotheses; ++h) {
    std::optional<Sphere> s;
    if (use_normals) {
      const std::size_t n = pts.with_normal.size();
      s = from_normals(pts, pts.with_normal[rng.below(n)], pts.with_normal[rng.below(n)]);
    } else {
      const std::size_t k[4] = {rng.below(pts.size()), rng.below(pts.size()), rng.below(pts.size()),
                                rng.below(pts.size())};
      s = from_four(pts, k);
    }
    if (!s || !within_bounds(s->radius, settings)) continue;
    const double cost = msac_cost(
        pts, scoring, [&](const Vec3d& p) { return s->deviation(p); }, settings);
    if (cost < best_cost) best_cost = cost, best = s;
  }
  if (!best) return std::nullopt;
  Sphere sphere = *best;
  auto deviate = [&](const Vec3d& p) { return sphere.deviation(p); };
  InlierSet inliers = select_inliers(pts, deviate, settings);
  auto residual = [](const Sphere& s, const Vec3d& p) { return (p - s.center).norm() - s.radius; };
  auto move = [](const Sphere& s, const Eigen::Matrix<double, 4, 1>& d) {
    return Sphere{s.center + d.head<3>(), s.radius + d[3]};
  };
  for (int round = 0; round < 2 && inliers.indices.size() >= 4; ++round) {
    sphere = refine_lm<4>(sphere, refine_points(pts, inliers.indices, settings), residual, move,
                          settings.refine_iterations);
    inliers = select_inliers(pts, deviate, settings);
  }
  if (inliers.indices.size() < 4 || !within_bounds(sphere.radius, settings)) return std::nullopt;
  // Coverage: the half-angle of the cap the inliers cover, against a hemisphere.
  const double half_angle = cap_half_angle(pts, inliers.indices, sphere.center);
  Fit fit;
  fit.model = SphereModel{sphere.center, sphere.radius};
  fit.inliers = inliers.indices.size();
  fit.rms = inliers.rms;
  fit.confidence =
      double(fit.inliers) / double(pts.size()) * std::min(1.0, half_angle / (M_PI / 2));
  return fit;
}

}  // namespace primlabel::primitives
