// CGAL Efficient RANSAC on primlabel's points and normals, shapes as primlabel Primitives (see
// cgal_ransac_peer.hpp). Only CGAL's public API: Efficient_RANSAC, its shape classes and the
// default random generator (reseeded so a run is repeatable).

#include "cgal_ransac_peer.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>
#include <CGAL/property_map.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/synth/true_primitives.hpp"

namespace primlabel::bench {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
// detect() reorders its input, so each point carries its index in the caller's cloud.
using PointWithNormal = std::tuple<Kernel::Point_3, Kernel::Vector_3, std::uint32_t>;
using Points = std::vector<PointWithNormal>;
using Traits = CGAL::Shape_detection::Efficient_RANSAC_traits<
    Kernel, Points, CGAL::Nth_of_tuple_property_map<0, PointWithNormal>,
    CGAL::Nth_of_tuple_property_map<1, PointWithNormal>>;
using Ransac = CGAL::Shape_detection::Efficient_RANSAC<Traits>;
using CgalPlane = CGAL::Shape_detection::Plane<Traits>;
using CgalCylinder = CGAL::Shape_detection::Cylinder<Traits>;
using CgalSphere = CGAL::Shape_detection::Sphere<Traits>;
using CgalTorus = CGAL::Shape_detection::Torus<Traits>;
using Vec3d = Eigen::Vector3d;
using C = PrimitiveClass;

Vec3d to_eigen(const Kernel::Point_3& p) { return {p.x(), p.y(), p.z()}; }
Vec3d to_eigen(const Kernel::Vector_3& v) { return {v.x(), v.y(), v.z()}; }

// The shape's points, in the input's indexing.
struct Members {
  const std::vector<Vec3f>& xyz;
  std::span<const Vec3f> normals;
  std::vector<std::uint32_t> indices;

  Vec3d centroid() const {
    Vec3d sum = Vec3d::Zero();
    for (const auto i : indices) sum += xyz[i].cast<double>();
    return sum / double(indices.size());
  }
  // Mean of normal . outward direction: > 0 when the normals (oriented to the sensor) point away
  // from the axis or centre, i.e. the surface is seen from outside (convex).
  bool convex(const Vec3d& center, const Vec3d* axis) const {
    double sum = 0;
    for (const auto i : indices) {
      Vec3d out = xyz[i].cast<double>() - center;
      if (axis) out -= out.dot(*axis) * *axis;
      sum += out.normalized().dot(normals[i].cast<double>());
    }
    return sum >= 0;
  }
  // The smallest and largest coordinate of the points along `direction` from `origin`.
  std::pair<double, double> extent(const Vec3d& origin, const Vec3d& direction) const {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto i : indices) {
      const double t = (xyz[i].cast<double>() - origin).dot(direction);
      lo = std::min(lo, t), hi = std::max(hi, t);
    }
    return {lo, hi};
  }
};

// The plane n.x + offset = 0 and the oriented rectangle its points cover.
primitives::PlaneModel plane_model(const Vec3d& normal, double offset, const Members& m) {
  primitives::PlaneModel model;
  model.normal = normal.normalized();
  model.offset = offset;
  // The in-plane principal axes of the points give the oriented rectangle they cover.
  const Vec3d mean = m.centroid();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto i : m.indices) {
    Vec3d d = m.xyz[i].cast<double>() - mean;
    d -= d.dot(model.normal) * model.normal;
    scatter += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
  model.axis_u = solver.eigenvectors().col(2).normalized();
  model.axis_v = model.normal.cross(model.axis_u).normalized();
  const auto [u_lo, u_hi] = m.extent(mean, model.axis_u);
  const auto [v_lo, v_hi] = m.extent(mean, model.axis_v);
  const Vec3d on_plane = mean - (model.normal.dot(mean) + model.offset) * model.normal;
  model.center = on_plane + 0.5 * (u_lo + u_hi) * model.axis_u + 0.5 * (v_lo + v_hi) * model.axis_v;
  model.extent_u = u_hi - u_lo;
  model.extent_v = v_hi - v_lo;
  if (model.extent_v > model.extent_u) {
    std::swap(model.extent_u, model.extent_v);
    std::swap(model.axis_u, model.axis_v);
  }
  return model;
}

primitives::CylinderModel cylinder_through(const Vec3d& origin, const Vec3d& axis, double radius,
                                           const Members& m) {
  primitives::CylinderModel model;
  model.axis = axis.normalized();
  model.radius = radius;
  const auto [lo, hi] = m.extent(origin, model.axis);
  model.center = origin + 0.5 * (lo + hi) * model.axis;
  model.height = hi - lo;
  return model;
}

// The plane a cylinder or sphere of huge radius is near the points: tangent where the direction
// from the axis (or centre) through their centroid meets the surface.
primitives::PlaneModel tangent_plane(const Vec3d& center, const Vec3d* axis, double radius,
                                     const Members& m) {
  Vec3d radial = m.centroid() - center;
  if (axis) radial -= radial.dot(*axis) * *axis;
  radial.normalize();
  return plane_model(radial, -radial.dot(center + radius * radial), m);
}

// The cylinder a torus of huge major radius is, near the points: the tube around the centre
// circle's tangent at the point of the circle nearest their centroid.
primitives::CylinderModel cylinder_of_torus(const primitives::TorusModel& torus, const Members& m) {
  Vec3d radial = m.centroid() - torus.center;
  radial -= radial.dot(torus.axis) * torus.axis;
  radial.normalize();
  const Vec3d on_circle = torus.center + torus.major_radius * radial;
  return cylinder_through(on_circle, torus.axis.cross(radial), torus.minor_radius, m);
}

// CGAL's shape as primlabel's model, before degenerate_limit.
primitives::Model raw_model(const Ransac::Shape& shape, const Members& m) {
  if (const auto* plane = dynamic_cast<const CgalPlane*>(&shape))
    // CGAL's Plane_3 convention: n.x + d = 0.
    return plane_model(to_eigen(plane->plane_normal()), plane->d(), m);
  if (const auto* cylinder = dynamic_cast<const CgalCylinder*>(&shape)) {
    const Kernel::Line_3 axis = cylinder->axis();
    return cylinder_through(to_eigen(axis.point()), to_eigen(axis.to_vector()), cylinder->radius(),
                            m);
  }
  if (const auto* sphere = dynamic_cast<const CgalSphere*>(&shape))
    return primitives::SphereModel{to_eigen(sphere->center()), sphere->radius()};
  if (const auto* torus = dynamic_cast<const CgalTorus*>(&shape))
    return primitives::TorusModel{to_eigen(torus->center()), to_eigen(torus->axis()).normalized(),
                                  torus->major_radius(), torus->minor_radius()};
  return std::monostate{};
}

// The taxonomy class of a model on these points: convex or concave by their normals.
std::uint32_t class_of(const primitives::Model& model, const Members& m) {
  if (std::holds_alternative<primitives::PlaneModel>(model)) return class_id(C::kPlane);
  if (const auto* c = std::get_if<primitives::CylinderModel>(&model))
    return class_id(m.convex(c->center, &c->axis) ? C::kCylinderConvex : C::kCylinderConcave);
  if (const auto* s = std::get_if<primitives::SphereModel>(&model))
    return class_id(m.convex(s->center, nullptr) ? C::kSphereConvex : C::kSphereConcave);
  if (std::holds_alternative<primitives::TorusModel>(model)) return class_id(C::kTorusConvex);
  return class_id(C::kUnknown);
}

}  // namespace

primitives::Model degenerate_limit(const primitives::Model& model, const std::vector<Vec3f>& xyz,
                                   std::span<const std::uint32_t> points, double limit) {
  if (!(limit > 0) || points.empty()) return model;
  const Members m{xyz, {}, {points.begin(), points.end()}};
  if (const auto* c = std::get_if<primitives::CylinderModel>(&model); c && c->radius > limit)
    return tangent_plane(c->center, &c->axis, c->radius, m);
  if (const auto* s = std::get_if<primitives::SphereModel>(&model); s && s->radius > limit)
    return tangent_plane(s->center, nullptr, s->radius, m);
  if (const auto* t = std::get_if<primitives::TorusModel>(&model); t && t->major_radius > limit)
    return cylinder_of_torus(*t, m);
  return model;
}

CgalRansacParameters CgalRansacParameters::for_spacing(double point_spacing) {
  CgalRansacParameters p;
  if (std::isfinite(point_spacing) && point_spacing > 0) p.cluster_epsilon = 4 * point_spacing;
  return p;
}

CgalDetections detect_with_cgal(const std::vector<Vec3f>& xyz, std::span<const Vec3f> normals,
                                const CgalRansacParameters& parameters) {
  if (normals.size() != xyz.size())
    throw std::invalid_argument("detect_with_cgal: one normal per point needed");
  Points points;
  points.reserve(xyz.size());
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    const Vec3f& n = normals[i];
    if (!is_finite(xyz[i]) || !is_finite(n) || n.squaredNorm() < 1e-12f) continue;
    points.emplace_back(Kernel::Point_3(xyz[i].x(), xyz[i].y(), xyz[i].z()),
                        Kernel::Vector_3(n.x(), n.y(), n.z()), std::uint32_t(i));
  }

  CgalDetections out;
  out.set.point_segment.assign(xyz.size(), primitives::kNoSegment);
  if (points.empty()) return out;
  CGAL::get_default_random() = CGAL::Random(static_cast<unsigned int>(parameters.seed));
  Ransac ransac;
  ransac.set_input(points);
  ransac.add_shape_factory<CgalPlane>();
  ransac.add_shape_factory<CgalCylinder>();
  ransac.add_shape_factory<CgalSphere>();
  ransac.add_shape_factory<CgalTorus>();
  Ransac::Parameters settings;
  settings.probability = parameters.probability;
  settings.min_points = parameters.min_points;
  settings.epsilon = parameters.epsilon;
  settings.cluster_epsilon = parameters.cluster_epsilon;
  settings.normal_threshold = parameters.normal_threshold;
  const auto start = std::chrono::steady_clock::now();
  ransac.detect(settings);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<std::pair<primitives::Primitive, std::vector<std::uint32_t>>> found;
  for (const auto& shape : ransac.shapes()) {
    Members members{xyz, normals, {}};
    for (const std::size_t k : shape->indices_of_assigned_points())
      members.indices.push_back(std::get<2>(points[k]));
    if (members.indices.empty()) continue;
    std::sort(members.indices.begin(), members.indices.end());
    primitives::Primitive p;
    const primitives::Model raw = raw_model(*shape, members);
    p.model = degenerate_limit(raw, xyz, members.indices, parameters.degenerate_radius);
    if (p.model.index() != raw.index()) ++out.degenerate;
    p.class_id = class_of(p.model, members);
    p.points = p.inliers = members.indices.size();
    p.first_point = members.indices.front();
    p.centroid = members.centroid();
    p.bounds_min = p.bounds_max = xyz[members.indices.front()].cast<double>();
    double squared = 0;
    for (const auto i : members.indices) {
      const Vec3d q = xyz[i].cast<double>();
      p.bounds_min = p.bounds_min.cwiseMin(q);
      p.bounds_max = p.bounds_max.cwiseMax(q);
      squared += std::pow(synth::distance_to(p.model, q), 2);
    }
    p.rms = std::sqrt(squared / double(members.indices.size()));
    p.confidence = 1;
    found.emplace_back(std::move(p), std::move(members.indices));
  }
  // Most points first, ties by lowest point (as primlabel orders its segments).
  std::stable_sort(found.begin(), found.end(), [](const auto& a, const auto& b) {
    return a.first.points != b.first.points ? a.first.points > b.first.points
                                            : a.first.first_point < b.first.first_point;
  });
  for (auto& [primitive, indices] : found) {
    for (const auto i : indices)
      out.set.point_segment[i] = std::uint32_t(out.set.primitives.size());
    out.set.primitives.push_back(std::move(primitive));
  }
  return out;
}

}  // namespace primlabel::bench
