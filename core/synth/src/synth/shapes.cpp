// Analytic ray intersection, part classes and feature curves of the synthetic shapes.
//
// Every shape is a closed solid described by the patches of its boundary; a ray's first hit is
// the nearest valid patch hit, so no patch needs to know which side the ray comes from.

#include "primlabel/synth/shapes.hpp"

#include <Eigen/Geometry>
#include <algorithm>

namespace primlabel::synth {
namespace {

constexpr double kParallel = 1e-15;

// Collects the nearest of several candidate hits within (t_min, t_max).
class Nearest {
 public:
  Nearest(double t_min, double t_max) : t_min_(t_min), best_(t_max) {}
  void offer(double t, int part, const Vec3d& normal) {
    if (t > t_min_ && t < best_) {
      best_ = t;
      part_ = part;
      normal_ = normal;
    }
  }
  double limit() const { return best_; }
  bool finish(SurfaceHit& hit) const {
    if (part_ < 0) return false;
    hit.t = best_;
    hit.part = part_;
    hit.normal = normal_.normalized();
    return true;
  }

 private:
  double t_min_, best_;
  int part_ = -1;
  Vec3d normal_ = Vec3d::Zero();
};

// Roots of |(o + t d)_xy| = radius (an infinite cylinder around the z axis), ascending.
int cylinder_roots(const Ray& ray, double radius, double t[2]) {
  const double a = ray.dir.x() * ray.dir.x() + ray.dir.y() * ray.dir.y();
  if (a < kParallel) return 0;
  const double b = ray.origin.x() * ray.dir.x() + ray.origin.y() * ray.dir.y();
  const double c =
      ray.origin.x() * ray.origin.x() + ray.origin.y() * ray.origin.y() - radius * radius;
  const double disc = b * b - a * c;
  if (disc < 0) return 0;
  const double s = std::sqrt(disc);
  t[0] = (-b - s) / a;
  t[1] = (-b + s) / a;
  return 2;
}

int sphere_roots(const Ray& ray, const Vec3d& center, double radius, double t[2]) {
  const Vec3d oc = ray.origin - center;
  const double b = oc.dot(ray.dir);
  const double disc = b * b - (oc.squaredNorm() - radius * radius);
  if (disc < 0) return 0;
  const double s = std::sqrt(disc);
  t[0] = -b - s;
  t[1] = -b + s;
  return 2;
}

bool plane_z(const Ray& ray, double z, double& t) {
  if (std::abs(ray.dir.z()) < kParallel) return false;
  t = (z - ray.origin.z()) / ray.dir.z();
  return true;
}

double radial(const Vec3d& p) { return std::hypot(p.x(), p.y()); }

Vec3d radial_dir(const Vec3d& p) { return Vec3d(p.x(), p.y(), 0.0); }

// Offers the hits of a horizontal annulus (inner <= rho <= outer) at height z.
void offer_disk(const Ray& ray, double z, double inner, double outer, int part, double normal_z,
                Nearest& nearest) {
  double t;
  if (!plane_z(ray, z, t)) return;
  const double rho = radial(ray.at(t));
  if (rho >= inner && rho <= outer) nearest.offer(t, part, Vec3d(0, 0, normal_z));
}

// Offers the hits of the cylinder rho = radius with z_lo <= z <= z_hi; normal_sign +1 points
// away from the axis (an outer wall), -1 toward it (an inner wall).
void offer_wall(const Ray& ray, double radius, double z_lo, double z_hi, int part,
                double normal_sign, Nearest& nearest) {
  double t[2];
  if (cylinder_roots(ray, radius, t) == 0) return;
  for (double ti : t) {
    const Vec3d p = ray.at(ti);
    if (p.z() >= z_lo && p.z() <= z_hi) nearest.offer(ti, part, normal_sign * radial_dir(p));
  }
}

// Signed distance to a torus with centre c, unit axis a, ring radius R and tube radius r.
struct TorusGeometry {
  Vec3d center;
  Vec3d axis;
  double major, tube;

  Vec3d core_point(const Vec3d& p) const {
    const Vec3d q = p - center;
    Vec3d w = q - q.dot(axis) * axis;
    const double n = w.norm();
    if (n < 1e-12)
      w = axis.unitOrthogonal();
    else
      w /= n;
    return center + major * w;
  }
  double sdf(const Vec3d& p) const { return (p - core_point(p)).norm() - tube; }
  Vec3d normal(const Vec3d& p) const { return (p - core_point(p)).normalized(); }
  // Distance of p from the axis line.
  double axial_radius(const Vec3d& p) const {
    const Vec3d q = p - center;
    return (q - q.dot(axis) * axis).norm();
  }
};

// Sphere tracing of a signed distance bound along the ray within the bounding sphere; `sdf`
// must never overestimate the distance to the surface. Returns the hit parameter or +inf.
template <typename Sdf>
double sphere_trace(const Ray& ray, const Vec3d& bound_center, double bound_radius, double t_min,
                    double t_max, Sdf sdf) {
  double roots[2];
  if (sphere_roots(ray, bound_center, bound_radius, roots) == 0) return INFINITY;
  double t = std::max(roots[0], t_min);
  const double end = std::min(roots[1], t_max);
  for (int step = 0; step < 200 && t <= end; ++step) {
    const double d = sdf(ray.at(t));
    if (d < 1e-8) return t > t_min ? t : INFINITY;
    t += d;
  }
  return INFINITY;
}

}  // namespace

// --- Feature ---------------------------------------------------------------------------------

Feature Feature::segment(Kind kind, const Vec3d& from, const Vec3d& to, std::uint32_t parts) {
  Feature f;
  f.kind = kind;
  f.geometry = Geometry::kSegment;
  f.a = from;
  f.b = to;
  f.parts = parts;
  return f;
}

Feature Feature::circle(Kind kind, const Vec3d& centre, const Vec3d& axis, double radius,
                        std::uint32_t parts) {
  Feature f;
  f.kind = kind;
  f.geometry = Geometry::kCircle;
  f.a = centre;
  f.b = axis.normalized();
  f.radius = radius;
  f.parts = parts;
  return f;
}

double Feature::distance(const Vec3d& p) const {
  if (geometry == Geometry::kSegment) {
    const Vec3d ab = b - a;
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (p - (a + s * ab)).norm();
  }
  const Vec3d q = p - a;
  const double along = q.dot(b);
  const double rho = (q - along * b).norm();
  return std::hypot(rho - radius, along);
}

// --- Box -------------------------------------------------------------------------------------

BoxShape::BoxShape(const Vec3d& size, bool bottom_edges)
    : size_(size),
      lo_(-0.5 * size.x(), -0.5 * size.y(), 0.0),
      hi_(0.5 * size.x(), 0.5 * size.y(), size.z()) {
  const double xs[2] = {lo_.x(), hi_.x()}, ys[2] = {lo_.y(), hi_.y()}, zs[2] = {lo_.z(), hi_.z()};
  using K = Feature::Kind;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      // Edges along x and y at height zs[j].
      if (j == 1 || bottom_edges) {
        features_.push_back(Feature::segment(K::kConvexEdge, Vec3d(lo_.x(), ys[i], zs[j]),
                                             Vec3d(hi_.x(), ys[i], zs[j])));
        features_.push_back(Feature::segment(K::kConvexEdge, Vec3d(xs[i], lo_.y(), zs[j]),
                                             Vec3d(xs[i], hi_.y(), zs[j])));
      }
      features_.push_back(Feature::segment(K::kConvexEdge, Vec3d(xs[i], ys[j], lo_.z()),
                                           Vec3d(xs[i], ys[j], hi_.z())));
    }
  bound_center_ = 0.5 * (lo_ + hi_);
  bound_radius_ = 0.5 * size_.norm();
}

bool BoxShape::intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const {
  double enter = -INFINITY, exit = INFINITY;
  int axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(ray.dir[i]) < kParallel) {
      if (ray.origin[i] < lo_[i] || ray.origin[i] > hi_[i]) return false;
      continue;
    }
    double ta = (lo_[i] - ray.origin[i]) / ray.dir[i];
    double tb = (hi_[i] - ray.origin[i]) / ray.dir[i];
    if (ta > tb) std::swap(ta, tb);
    if (ta > enter) {
      enter = ta;
      axis = i;
    }
    exit = std::min(exit, tb);
  }
  if (axis < 0 || enter > exit || enter <= t_min || enter >= t_max) return false;
  const bool positive = ray.dir[axis] > 0;  // enters through the low face
  hit.t = enter;
  hit.part = 2 * axis + (positive ? 0 : 1);
  hit.normal = Vec3d::Zero();
  hit.normal[axis] = positive ? -1.0 : 1.0;
  return true;
}

double BoxShape::distance_outside(const Vec3d& p) const {
  return (lo_ - p).cwiseMax(p - hi_).cwiseMax(0.0).norm();
}

double BoxShape::footprint_inset(const Vec3d& p) const {
  const double inset = std::min(std::min(p.x() - lo_.x(), hi_.x() - p.x()),
                                std::min(p.y() - lo_.y(), hi_.y() - p.y()));
  return std::max(inset, 0.0);
}

// --- Can -------------------------------------------------------------------------------------

CanShape::CanShape(double radius, double height) : radius_(radius), height_(height) {
  features_.push_back(Feature::circle(Feature::Kind::kConvexEdge, Vec3d(0, 0, height),
                                      Vec3d::UnitZ(), radius, 0b011));
  bound_center_ = Vec3d(0, 0, 0.5 * height);
  bound_radius_ = std::hypot(radius, 0.5 * height);
}

bool CanShape::intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const {
  Nearest nearest(t_min, t_max);
  offer_wall(ray, radius_, 0.0, height_, 0, 1.0, nearest);
  offer_disk(ray, height_, 0.0, radius_, 1, 1.0, nearest);
  offer_disk(ray, 0.0, 0.0, radius_, 2, -1.0, nearest);
  return nearest.finish(hit);
}

PrimitiveClass CanShape::surface_class(int part, const Vec3d&) const {
  return part == 0 ? PrimitiveClass::kCylinderConvex : PrimitiveClass::kPlane;
}

double CanShape::distance_outside(const Vec3d& p) const {
  const double d_rho = std::max(radial(p) - radius_, 0.0);
  const double d_z = std::max({-p.z(), p.z() - height_, 0.0});
  return std::hypot(d_rho, d_z);
}

double CanShape::footprint_inset(const Vec3d& p) const {
  return std::max(radius_ - radial(p), 0.0);
}

// --- Lying can ------------------------------------------------------------------------------

LyingCanShape::LyingCanShape(double radius, double length)
    : radius_(radius), length_(length), upright_(radius, length) {
  using K = Feature::Kind;
  features_.push_back(Feature::circle(K::kConvexEdge, Vec3d(0.5 * length, 0, radius),
                                      Vec3d::UnitX(), radius, 0b011));
  features_.push_back(Feature::circle(K::kConvexEdge, Vec3d(-0.5 * length, 0, radius),
                                      Vec3d::UnitX(), radius, 0b101));
  bound_center_ = Vec3d(0, 0, radius);
  bound_radius_ = std::hypot(radius, 0.5 * length);
}

bool LyingCanShape::intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const {
  // The upright frame is this one mirrored (x and z swapped, then shifted): directions map alike.
  const Ray upright{upright_from_local(ray.origin), Vec3d(ray.dir.z(), ray.dir.y(), ray.dir.x())};
  if (!upright_.intersect(upright, t_min, t_max, hit)) return false;
  hit.normal = Vec3d(hit.normal.z(), hit.normal.y(), hit.normal.x());
  return true;  // parts coincide: 0 side, 1 the lid (+x), 2 the bottom (-x)
}

PrimitiveClass LyingCanShape::surface_class(int part, const Vec3d&) const {
  return part == 0 ? PrimitiveClass::kCylinderConvex : PrimitiveClass::kPlane;
}

double LyingCanShape::distance_outside(const Vec3d& p) const {
  return upright_.distance_outside(upright_from_local(p));
}

// --- Mug / cup -------------------------------------------------------------------------------

MugShape::MugShape(double radius, double height, double wall, double floor, const Handle& handle)
    : radius_(radius),
      height_(height),
      inner_radius_(radius - wall),
      floor_(floor),
      handle_(handle) {
  using K = Feature::Kind;
  // The rim applies to both walls, the lip and the handle's top (all within reach of the lip).
  features_.push_back(
      Feature::circle(K::kRim, Vec3d(0, 0, height), Vec3d::UnitZ(), radius - 0.5 * wall, 0b100111));
  features_.push_back(
      Feature::circle(K::kConcaveEdge, Vec3d(0, 0, floor), Vec3d::UnitZ(), inner_radius_, 0b1010));
  handle_center_ = Vec3d(radius + handle.offset, 0.0, handle.height);
  bound_center_ = Vec3d(0, 0, 0.5 * height);
  bound_radius_ = std::hypot(footprint_radius(), 0.5 * height);
}

double MugShape::footprint_radius() const {
  if (handle_.major_radius <= 0) return radius_;
  return radius_ + handle_.offset + handle_.major_radius + handle_.tube_radius;
}

bool MugShape::intersect_handle(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const {
  const TorusGeometry torus{handle_center_, Vec3d::UnitY(), handle_.major_radius,
                            handle_.tube_radius};
  // The ring is clipped to the outside of the outer wall: max() of the two distance bounds.
  auto sdf = [&](const Vec3d& p) { return std::max(torus.sdf(p), radius_ - radial(p)); };
  const double t = sphere_trace(ray, handle_center_, handle_.major_radius + handle_.tube_radius,
                                t_min, t_max, sdf);
  if (!std::isfinite(t)) return false;
  const Vec3d p = ray.at(t);
  if (torus.sdf(p) < radius_ - radial(p) - 1e-7) return false;  // stopped on the wall, not the ring
  hit.t = t;
  hit.part = 5;
  hit.normal = torus.normal(p);
  return true;
}

bool MugShape::intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const {
  Nearest nearest(t_min, t_max);
  offer_wall(ray, radius_, 0.0, height_, 0, 1.0, nearest);
  offer_wall(ray, inner_radius_, floor_, height_, 1, -1.0, nearest);
  offer_disk(ray, height_, inner_radius_, radius_, 2, 1.0, nearest);
  offer_disk(ray, floor_, 0.0, inner_radius_, 3, 1.0, nearest);
  offer_disk(ray, 0.0, 0.0, radius_, 4, -1.0, nearest);
  if (handle_.major_radius > 0) {
    SurfaceHit handle_hit;
    if (intersect_handle(ray, t_min, nearest.limit(), handle_hit))
      nearest.offer(handle_hit.t, handle_hit.part, handle_hit.normal);
  }
  return nearest.finish(hit);
}

PrimitiveClass MugShape::surface_class(int part, const Vec3d&) const {
  switch (part) {
    case 0:
      return PrimitiveClass::kCylinderConvex;
    case 1:
      return PrimitiveClass::kCylinderConcave;
    case 2:
      return PrimitiveClass::kTorusConvex;  // the lip is always within the rim's reach
    case 5:
      return PrimitiveClass::kTorusConvex;
    default:
      return PrimitiveClass::kPlane;
  }
}

double MugShape::distance_outside(const Vec3d& p) const {
  const double d_rho = std::max(radial(p) - radius_, 0.0);
  const double d_z = std::max({-p.z(), p.z() - height_, 0.0});
  return std::hypot(d_rho, d_z);
}

double MugShape::footprint_inset(const Vec3d& p) const {
  return std::max(radius_ - radial(p), 0.0);
}

// --- Bowl ------------------------------------------------------------------------------------

BowlShape::BowlShape(double radius, double rim_drop) : radius_(radius) {
  foot_ = 0.35 * radius;
  center_z_ = std::sqrt(radius * radius - foot_ * foot_);
  // The wall must leave the inner sphere's bottom above the table.
  const double wall = std::max(0.004, radius - center_z_ + 0.002);
  inner_radius_ = radius - wall;
  rim_z_ = center_z_ - rim_drop;
  outer_rim_radius_ = std::sqrt(radius * radius - rim_drop * rim_drop);
  inner_rim_radius_ = std::sqrt(inner_radius_ * inner_radius_ - rim_drop * rim_drop);
  outer_rim_radius_max_ = outer_rim_radius_;
  features_.push_back(Feature::circle(Feature::Kind::kRim, Vec3d(0, 0, rim_z_), Vec3d::UnitZ(),
                                      0.5 * (inner_rim_radius_ + outer_rim_radius_), 0b0111));
  bound_center_ = Vec3d(0, 0, 0.5 * rim_z_);
  bound_radius_ = std::hypot(outer_rim_radius_, 0.5 * rim_z_);
}

bool BowlShape::intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const {
  Nearest nearest(t_min, t_max);
  const Vec3d center(0, 0, center_z_);
  double t[2];
  if (sphere_roots(ray, center, radius_, t))
    for (double ti : t) {
      const Vec3d p = ray.at(ti);
      if (p.z() >= 0.0 && p.z() <= rim_z_) nearest.offer(ti, 0, p - center);
    }
  if (sphere_roots(ray, center, inner_radius_, t))
    for (double ti : t) {
      const Vec3d p = ray.at(ti);
      if (p.z() <= rim_z_) nearest.offer(ti, 1, center - p);
    }
  offer_disk(ray, rim_z_, inner_rim_radius_, outer_rim_radius_, 2, 1.0, nearest);
  offer_disk(ray, 0.0, 0.0, foot_, 3, -1.0, nearest);
  return nearest.finish(hit);
}

PrimitiveClass BowlShape::surface_class(int part, const Vec3d&) const {
  switch (part) {
    case 0:
      return PrimitiveClass::kSphereConvex;
    case 1:
      return PrimitiveClass::kSphereConcave;
    case 2:
      return PrimitiveClass::kTorusConvex;
    default:
      return PrimitiveClass::kPlane;
  }
}

double BowlShape::distance_outside(const Vec3d& p) const {
  const double sphere = (p - Vec3d(0, 0, center_z_)).norm() - radius_;
  return std::max({sphere, -p.z(), p.z() - rim_z_, 0.0});
}

double BowlShape::footprint_inset(const Vec3d& p) const { return std::max(foot_ - radial(p), 0.0); }

// --- Ball ------------------------------------------------------------------------------------

BallShape::BallShape(double radius) : radius_(radius) {
  bound_center_ = Vec3d(0, 0, radius);
  bound_radius_ = radius;
}

bool BallShape::intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const {
  Nearest nearest(t_min, t_max);
  double t[2];
  if (sphere_roots(ray, bound_center_, radius_, t))
    for (double ti : t) nearest.offer(ti, 0, ray.at(ti) - bound_center_);
  return nearest.finish(hit);
}

double BallShape::distance_outside(const Vec3d& p) const {
  return std::max((p - bound_center_).norm() - radius_, 0.0);
}

// --- Torus -----------------------------------------------------------------------------------

TorusShape::TorusShape(double major_radius, double tube_radius)
    : major_(major_radius), tube_(tube_radius) {
  bound_center_ = Vec3d(0, 0, tube_radius);
  bound_radius_ = major_radius + tube_radius;
}

bool TorusShape::intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const {
  const TorusGeometry torus{bound_center_, Vec3d::UnitZ(), major_, tube_};
  const double t = sphere_trace(ray, bound_center_, bound_radius_, t_min, t_max,
                                [&](const Vec3d& p) { return torus.sdf(p); });
  if (!std::isfinite(t)) return false;
  hit.t = t;
  hit.part = 0;
  hit.normal = torus.normal(ray.at(t));
  return true;
}

PrimitiveClass TorusShape::surface_class(int, const Vec3d& p) const {
  return radial(p) >= major_ ? PrimitiveClass::kTorusConvex : PrimitiveClass::kTorusConcave;
}

double TorusShape::distance_outside(const Vec3d& p) const {
  const TorusGeometry torus{bound_center_, Vec3d::UnitZ(), major_, tube_};
  return std::max(torus.sdf(p), 0.0);
}

}  // namespace primlabel::synth
