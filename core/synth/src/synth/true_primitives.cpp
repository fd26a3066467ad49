// The true primitives of a synthetic scene (see true_primitives.hpp), from each shape's own
// parameters in its local frame (shapes.hpp gives the frames), moved to the world.

#include "primlabel/synth/true_primitives.hpp"

#include <cmath>
#include <limits>

#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/synth/shapes.hpp"

namespace primlabel::synth {
namespace {

using primitives::CylinderModel;
using primitives::PlaneModel;
using primitives::SphereModel;
using primitives::TorusModel;
using primitives::Vec3d;
using C = PrimitiveClass;

// Collects one object's primitives, given in its local frame.
struct ObjectPrimitives {
  int object;
  const Eigen::Isometry3d& world_from_local;
  std::vector<TruePrimitive>& out;

  Vec3d point(const Vec3d& local) const { return world_from_local * local; }
  Vec3d direction(const Vec3d& local) const { return world_from_local.linear() * local; }

  void add(C cls, primitives::Model model) {
    primitives::Primitive p;
    p.class_id = class_id(cls);
    p.model = std::move(model);
    p.confidence = 1;
    out.push_back({object, std::move(p)});
  }

  // A rectangle of size_u x size_v around `center` with outward normal `normal`.
  void plane(const Vec3d& center, const Vec3d& normal, const Vec3d& u, double size_u,
             const Vec3d& v, double size_v) {
    PlaneModel m;
    m.center = point(center);
    m.normal = direction(normal);
    m.offset = -m.normal.dot(m.center);
    const bool u_longer = size_u >= size_v;  // extent_u >= extent_v, as the fitter reports
    m.axis_u = direction(u_longer ? u : v);
    m.axis_v = direction(u_longer ? v : u);
    m.extent_u = std::max(size_u, size_v);
    m.extent_v = std::min(size_u, size_v);
    add(C::kPlane, m);
  }
  void disc(const Vec3d& center, const Vec3d& normal, double radius) {
    const Vec3d u = std::abs(normal.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY();
    const Vec3d w = (u - u.dot(normal) * normal).normalized();
    plane(center, normal, w, 2 * radius, normal.cross(w), 2 * radius);
  }
  void cylinder(C cls, const Vec3d& center, const Vec3d& axis, double radius, double height) {
    add(cls, CylinderModel{point(center), direction(axis), radius, height});
  }
  void sphere(C cls, const Vec3d& center, double radius) {
    add(cls, SphereModel{point(center), radius});
  }
};

void add_shape(const Shape& shape, ObjectPrimitives& o) {
  const Vec3d x = Vec3d::UnitX(), y = Vec3d::UnitY(), z = Vec3d::UnitZ();
  if (const auto* box = dynamic_cast<const BoxShape*>(&shape)) {
    const Vec3d s = box->size();
    o.plane({-s.x() / 2, 0, s.z() / 2}, -x, y, s.y(), z, s.z());
    o.plane({s.x() / 2, 0, s.z() / 2}, x, y, s.y(), z, s.z());
    o.plane({0, -s.y() / 2, s.z() / 2}, -y, x, s.x(), z, s.z());
    o.plane({0, s.y() / 2, s.z() / 2}, y, x, s.x(), z, s.z());
    o.plane({0, 0, 0}, -z, x, s.x(), y, s.y());
    o.plane({0, 0, s.z()}, z, x, s.x(), y, s.y());
  } else if (const auto* can = dynamic_cast<const CanShape*>(&shape)) {
    const double r = can->radius(), h = can->height();
    o.cylinder(C::kCylinderConvex, {0, 0, h / 2}, z, r, h);
    o.disc({0, 0, h}, z, r);
    o.disc({0, 0, 0}, -z, r);
  } else if (const auto* lying = dynamic_cast<const LyingCanShape*>(&shape)) {
    const double r = lying->radius(), l = lying->length();
    o.cylinder(C::kCylinderConvex, {0, 0, r}, x, r, l);
    o.disc({l / 2, 0, r}, x, r);
    o.disc({-l / 2, 0, r}, -x, r);
  } else if (const auto* mug = dynamic_cast<const MugShape*>(&shape)) {
    const double h = mug->height(), f = mug->floor_height();
    o.cylinder(C::kCylinderConvex, {0, 0, h / 2}, z, mug->outer_radius(), h);
    o.cylinder(C::kCylinderConcave, {0, 0, (f + h) / 2}, z, mug->inner_radius(), h - f);
    o.disc({0, 0, f}, z, mug->inner_radius());
    o.disc({0, 0, 0}, -z, mug->outer_radius());
  } else if (const auto* bowl = dynamic_cast<const BowlShape*>(&shape)) {
    const Vec3d center(0, 0, bowl->center_height());
    o.sphere(C::kSphereConvex, center, bowl->outer_radius());
    o.sphere(C::kSphereConcave, center, bowl->inner_radius());
  } else if (const auto* ball = dynamic_cast<const BallShape*>(&shape)) {
    o.sphere(C::kSphereConvex, {0, 0, ball->radius()}, ball->radius());
  } else if (const auto* ring = dynamic_cast<const TorusShape*>(&shape)) {
    o.add(C::kTorusConvex, TorusModel{o.point({0, 0, ring->tube_radius()}), o.direction(z),
                                      ring->major_radius(), ring->tube_radius()});
  }
}

bool counts_for(std::uint32_t point_class, std::uint32_t primitive_class) {
  const auto torus = [](std::uint32_t c) {
    return c == class_id(C::kTorusConvex) || c == class_id(C::kTorusConcave);
  };
  return point_class == primitive_class || (torus(point_class) && torus(primitive_class));
}

struct Distance {
  const Vec3d& p;
  double operator()(std::monostate) const { return std::numeric_limits<double>::infinity(); }
  double operator()(const PlaneModel& m) const {
    const Vec3d d = p - m.center;
    const double beyond_u = std::max(std::abs(d.dot(m.axis_u)) - m.extent_u / 2, 0.0);
    const double beyond_v = std::max(std::abs(d.dot(m.axis_v)) - m.extent_v / 2, 0.0);
    return std::sqrt(std::pow(d.dot(m.normal), 2) + beyond_u * beyond_u + beyond_v * beyond_v);
  }
  double operator()(const CylinderModel& m) const {
    const Vec3d d = p - m.center;
    const double along = d.dot(m.axis);
    const double radial = (d - along * m.axis).norm();
    return std::hypot(radial - m.radius, std::max(std::abs(along) - m.height / 2, 0.0));
  }
  double operator()(const SphereModel& m) const {
    return std::abs((p - m.center).norm() - m.radius);
  }
  double operator()(const TorusModel& m) const {
    const Vec3d d = p - m.center;
    const double along = d.dot(m.axis);
    const double radial = (d - along * m.axis).norm();
    return std::abs(std::hypot(radial - m.major_radius, along) - m.minor_radius);
  }
  double operator()(const primitives::LineModel& m) const {
    const double t = std::clamp((p - m.center).dot(m.direction), -m.length / 2, m.length / 2);
    return (p - m.center - t * m.direction).norm();
  }
};

}  // namespace

std::vector<TruePrimitive> true_primitives(const Scene& scene) {
  std::vector<TruePrimitive> out;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    ObjectPrimitives collect{int(i), scene.objects[i].world_from_local, out};
    add_shape(*scene.objects[i].shape, collect);
  }
  return out;
}

double distance_to(const primitives::Model& model, const Vec3d& p) {
  return std::visit(Distance{p}, model);
}

void count_points_on(std::vector<TruePrimitive>& truth, const PointCloud& cloud, double tolerance) {
  for (TruePrimitive& t : truth) t.primitive.points = t.own_points = 0;
  const FloatField* object = cloud.find_field("object");
  if (!object || !cloud.has_labels()) return;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!is_finite(cloud.xyz[i])) continue;
    const int owner = int(object->values[i]);
    const Vec3d p = cloud.xyz[i].cast<double>();
    TruePrimitive* nearest = nullptr;
    double nearest_distance = tolerance;
    for (TruePrimitive& t : truth) {
      if (t.object != owner || !counts_for(cloud.labels[i], t.primitive.class_id)) continue;
      const double d = distance_to(t.primitive.model, p);
      if (d > tolerance) continue;
      ++t.primitive.points;
      if (!nearest || d < nearest_distance) nearest = &t, nearest_distance = d;
    }
    if (nearest) ++nearest->own_points;
  }
}

}  // namespace primlabel::synth
