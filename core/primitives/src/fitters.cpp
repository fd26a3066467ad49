#include "primlabel/primitives/fitters.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "fit_support.hpp"

namespace primlabel::primitives {
namespace {

using detail::Deviation;

// A point's deviation from a fitted model: signed distance and the surface normal there.
Deviation deviation(const Model& model, const Vec3d& p) {
  if (const auto* plane = std::get_if<PlaneModel>(&model))
    return {plane->normal.dot(p) + plane->offset, plane->normal};
  if (const auto* c = std::get_if<CylinderModel>(&model)) {
    const Vec3d q = p - c->center;
    const Vec3d r = q - q.dot(c->axis) * c->axis;
    const double rho = r.norm();
    return {rho - c->radius, rho > 0 ? Vec3d(r / rho) : Vec3d::Zero()};
  }
  if (const auto* s = std::get_if<SphereModel>(&model)) {
    const Vec3d q = p - s->center;
    const double rho = q.norm();
    return {rho - s->radius, rho > 0 ? Vec3d(q / rho) : Vec3d::Zero()};
  }
  if (const auto* t = std::get_if<TorusModel>(&model)) {
    const Vec3d q = p - t->center;
    const double z = q.dot(t->axis);
    const Vec3d radial = q - z * t->axis;
    const double rho = radial.norm();
    const Vec3d u = rho > 0 ? Vec3d(radial / rho) : t->axis.unitOrthogonal();
    const Vec3d tube = (rho - t->major_radius) * u + z * t->axis;
    const double d = tube.norm();
    return {d - t->minor_radius, d > 0 ? Vec3d(tube / d) : Vec3d::Zero()};
  }
  return {};
}

// Free parameters of a model's surface (the extents of planes and cylinders are read off the
// inliers, not fitted).
int parameters(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kPlane:
      return 3;
    case PrimitiveKind::kSphere:
      return 4;
    case PrimitiveKind::kCylinder:
      return 5;
    case PrimitiveKind::kTorus:
      return 7;
    default:
      return 0;
  }
}

// Description length (BIC, the noise variance unknown) of the segment's points under a fit:
// n ln(S / n) + k ln n, where S sums each point's squared distance truncated at the inlier band
// (a point outside the band, or whose normal disagrees, costs the band's square: MSAC's cost) and
// k counts the surface's parameters. Residuals under a thousandth of the band are below any
// scanner's resolution and count as that (noise-free points would otherwise give ln 0).
double description_length(const detail::Points& pts, const Model& model, PrimitiveKind kind,
                          const FitSettings& settings) {
  const double t = settings.distance_threshold, t2 = t * t;
  const double floor2 = 1e-6 * t2;
  const double min_cos = std::cos(settings.normal_angle_deg * detail::kDeg);
  double sum = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Deviation d = deviation(model, pts.p[i]);
    const double d2 = d.distance * d.distance;
    sum += (d2 < t2 && detail::agrees(pts, i, d.normal, min_cos)) ? std::max(d2, floor2) : t2;
  }
  const double n = double(pts.size());
  return n * std::log(sum / n) + parameters(kind) * std::log(n);
}

// The simpler surfaces a curved fit must beat on the same points.
std::vector<PrimitiveKind> simpler_than(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kCylinder:
    case PrimitiveKind::kSphere:
      return {PrimitiveKind::kPlane};
    case PrimitiveKind::kTorus:
      return {PrimitiveKind::kPlane, PrimitiveKind::kCylinder, PrimitiveKind::kSphere};
    default:
      return {};
  }
}

std::optional<Fit> fit_one(PrimitiveKind kind, const SegmentPoints& points,
                           const FitSettings& settings, std::uint64_t seed) {
  switch (kind) {
    case PrimitiveKind::kPlane:
      return fit_plane(points, settings, seed);
    case PrimitiveKind::kCylinder:
      return fit_cylinder(points, settings, seed);
    case PrimitiveKind::kSphere:
      return fit_sphere(points, settings, seed);
    case PrimitiveKind::kTorus:
      return fit_torus(points, settings, seed);
    case PrimitiveKind::kLine:
      return fit_line(points, settings, seed);
    case PrimitiveKind::kSegment:
      break;
  }
  return std::nullopt;
}

}  // namespace

void FitSettings::validate() const {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("primitive fit: " + what);
  };
  if (!(distance_threshold > 0) || !std::isfinite(distance_threshold))
    fail("distance threshold must be finite and > 0");
  if (!(normal_angle_deg > 0 && normal_angle_deg <= 90)) fail("normal angle must be in (0, 90]");
  if (hypotheses < 1 || hypotheses > 100000) fail("hypotheses must be in [1, 100000]");
  if (max_scoring_points < 10 || max_refine_points < 10)
    fail("scoring and refinement points must be at least 10");
  if (refine_iterations < 0 || refine_iterations > 1000)
    fail("refine iterations must be in [0, 1000]");
  if (!(min_radius >= 0 && min_radius < max_radius) || !std::isfinite(max_radius))
    fail("radius bounds must be finite with 0 <= min < max");
}

bool explains_better_than_simpler(PrimitiveKind kind, const Fit& fit, const SegmentPoints& points,
                                  const FitSettings& settings, std::uint64_t seed) {
  const std::vector<PrimitiveKind> simpler = simpler_than(kind);
  if (simpler.empty()) return true;
  const detail::Points pts = detail::gather(points);
  if (pts.size() < 2) return true;
  const double own = description_length(pts, fit.model, kind, settings);
  for (PrimitiveKind other : simpler) {
    const std::optional<Fit> alternative = fit_one(other, points, settings, seed);
    if (alternative && description_length(pts, alternative->model, other, settings) <= own)
      return false;
  }
  return true;
}

std::optional<Fit> fit_model(PrimitiveKind kind, const SegmentPoints& points,
                             const FitSettings& settings, std::uint64_t seed) {
  std::optional<Fit> fit = fit_one(kind, points, settings, seed);
  if (fit && settings.prefer_simpler &&
      !explains_better_than_simpler(kind, *fit, points, settings, seed))
    return std::nullopt;
  return fit;
}

}  // namespace primlabel::primitives
