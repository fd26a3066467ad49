// The fitted ground truth of a scene: the table frame, a model per object segment, and the
// synthetic rule on the fitted scene (synth/fitted_truth.hpp).

#include <algorithm>
#include <map>
#include <stdexcept>

#include "primlabel/geometry/normals.hpp"
#include "primlabel/geometry/parallel.hpp"
#include "primlabel/synth/fitted_truth.hpp"
#include "primlabel/tabletop/plane_fit.hpp"
#include "shape_fit.hpp"

namespace primlabel::synth {
namespace {

using fit::Vec3d;

// The table plane (MSAC + least squares on the table segment), its normal toward the sensor, as
// the truth frame: z along the normal, z = 0 on the plane, x along the camera's x axis.
Eigen::Isometry3d fit_table_frame(const PointCloud& cloud, const std::vector<int>& segments,
                                  std::uint64_t seed) {
  std::vector<std::uint32_t> table;
  for (std::uint32_t i = 0; i < cloud.size(); ++i)
    if (segments[i] == 0 && is_finite(cloud.xyz[i])) table.push_back(i);
  tabletop::PlaneFitOptions options;
  options.distance_threshold = 0.01f;
  options.seed = seed;
  const tabletop::PlaneFit fit = tabletop::fit_plane(cloud.xyz, table, options);
  if (fit.status != tabletop::PlaneFitStatus::kOk)
    throw std::invalid_argument("no table plane in the table segment: " + fit.message);
  Vec3d n = fit.plane.head<3>().cast<double>().normalized();
  double d = fit.plane[3] / fit.plane.head<3>().cast<double>().norm();
  const Vec3d sensor = cloud.viewpoint.origin.cast<double>();
  if (n.dot(sensor) + d < 0) n = -n, d = -d;
  Vec3d x = (cloud.viewpoint.orientation.cast<double>() * Vec3d::UnitX());
  x = (x - x.dot(n) * n).normalized();
  Eigen::Matrix3d axes;  // columns: the truth frame's axes in the cloud frame
  axes << x, n.cross(x), n;
  Eigen::Isometry3d cloud_from_table = Eigen::Isometry3d::Identity();
  cloud_from_table.linear() = axes;
  cloud_from_table.translation() = -d * n;  // the plane's point nearest the cloud origin
  return cloud_from_table.inverse();
}

FittedObject choose_model(int segment, const fit::SegmentPoints& points,
                          const ObjectTruthOptions& options) {
  const fit::FitSettings settings{options.contact_tolerance,
                                  options.seed + static_cast<std::uint64_t>(segment)};
  FittedObject chosen;
  chosen.segment = segment;
  chosen.points = points.p.size();
  if (points.p.size() < options.min_segment_points) return chosen;
  const auto box = fit::fit_box(points, settings);
  const auto cylinder = fit::fit_cylinder(points, settings);
  fit::Evidence box_evidence, cylinder_evidence;
  if (box) box_evidence = fit::evaluate(*box, points);
  if (cylinder) cylinder_evidence = fit::evaluate(*cylinder, points);
  const bool take_box = box && (!cylinder || box_evidence.cost <= cylinder_evidence.cost);
  if (box || cylinder) {
    chosen = take_box ? *box : *cylinder;
    const fit::Evidence& e = take_box ? box_evidence : cylinder_evidence;
    chosen.inliers = e.inliers;
    chosen.rms = e.rms;
  }
  chosen.segment = segment;
  chosen.points = points.p.size();
  chosen.box_cost = box ? box_evidence.cost : NAN;
  chosen.cylinder_cost = cylinder ? cylinder_evidence.cost : NAN;
  chosen.bound = fit::quantile(points.bound, 0.5);
  const double z = fit::quantile(points.depth, 0.5);
  chosen.max_rms = options.rms_base + options.rms_z2 * z * z;
  if (chosen.inlier_share() < options.min_inlier_share || chosen.rms > chosen.max_rms)
    chosen.kind = FittedKind::kUnfitted;
  return chosen;
}

// A solid cannot lie inside another: a segment whose points are mostly inside another fitted
// solid (deeper than their bound, or facing into it) is part of a vessel's inside (the floor of
// a pot), not an object of its own.
void reject_nested(std::vector<FittedObject>& objects,
                   const std::vector<fit::SegmentPoints>& points) {
  std::vector<bool> nested(objects.size(), false);
  for (std::size_t a = 0; a < objects.size(); ++a) {
    if (objects[a].kind == FittedKind::kUnfitted) continue;
    for (std::size_t b = 0; b < objects.size() && !nested[a]; ++b) {
      if (a == b || objects[b].kind == FittedKind::kUnfitted) continue;
      const auto shape = fit::make_shape(objects[b]);
      const Eigen::Isometry3d local_from_table = objects[b].table_from_local.inverse();
      std::size_t inside = 0;
      for (std::size_t i = 0; i < points[a].p.size(); ++i) {
        const Vec3d local = local_from_table * points[a].p[i];
        if (shape->distance_outside(local) > 0) continue;
        const fit::SurfacePoint sp = fit::closest_surface(objects[b], local);
        const Vec3d normal = local_from_table.linear() * points[a].n[i];
        inside += sp.distance > points[a].bound[i] || normal.dot(sp.normal) < -0.5;
      }
      nested[a] = 2 * inside > points[a].p.size();
    }
  }
  for (std::size_t a = 0; a < objects.size(); ++a)
    if (nested[a]) objects[a].kind = FittedKind::kUnfitted;
}

}  // namespace

std::string_view fitted_kind_name(FittedKind kind) {
  switch (kind) {
    case FittedKind::kBox:
      return "box";
    case FittedKind::kUprightCylinder:
      return "upright-cylinder";
    case FittedKind::kLyingCylinder:
      return "lying-cylinder";
    case FittedKind::kUnfitted:
      break;
  }
  return "unfitted";
}

std::size_t ObjectTruth::count(FittedKind kind) const {
  std::size_t n = 0;
  for (const FittedObject& o : objects) n += o.kind == kind;
  return n;
}

std::vector<int> mosd_segments(const std::vector<std::uint32_t>& labels) {
  std::vector<int> segments(labels.size(), -1);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (is_mosd_table_label(labels[i])) segments[i] = 0;
    if (is_mosd_object_label(labels[i])) segments[i] = static_cast<int>(labels[i]);
  }
  return segments;
}

std::vector<int> synthetic_segments(const PointCloud& cloud) {
  const FloatField* object = cloud.find_field("object");
  if (!object || object->count != 1)
    throw std::invalid_argument("no `object` field (a primlabel-synth scene has one)");
  std::vector<int> segments(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    segments[i] = std::isfinite(object->values[i]) ? static_cast<int>(object->values[i]) : -1;
  return segments;
}

ObjectTruth fit_object_truth(const PointCloud& cloud, const std::vector<int>& segments,
                             const ObjectTruthOptions& options, const RunContext& context,
                             const NeighborSearch* search) {
  if (segments.size() != cloud.size())
    throw std::invalid_argument("fit_object_truth: one segment id per point is needed");
  ObjectTruth truth;
  truth.labels.assign(cloud.size(), class_id(PrimitiveClass::kUnknown));
  truth.table_from_cloud = fit_table_frame(cloud, segments, options.seed);

  PointCloud work;  // normals only: the caller's cloud stays as it is
  work.xyz = cloud.xyz;
  work.width = cloud.width;
  work.height = cloud.height;
  work.viewpoint = cloud.viewpoint;
  // Only the objects' points need a normal (the table is fitted by position alone).
  std::vector<std::uint8_t> on_object(cloud.size(), 0);
  for (std::size_t i = 0; i < cloud.size(); ++i) on_object[i] = segments[i] > 0;
  NormalOptions normal_options;
  normal_options.neighborhood = Neighborhood::Hybrid(options.normal_radius, 256);
  normal_options.wanted = on_object;
  estimate_normals(work, normal_options, context, search);

  // Per point: residual bound from its depth along the sensor's view axis.
  const Eigen::Isometry3d& t = truth.table_from_cloud;
  const Eigen::Matrix3d sensor_from_cloud =
      cloud.viewpoint.orientation.cast<double>().inverse().toRotationMatrix();
  const Vec3d origin = cloud.viewpoint.origin.cast<double>();
  auto depth = [&](const Vec3f& p) {
    return (sensor_from_cloud * (p.cast<double>() - origin)).z();
  };
  auto bound = [&](const Vec3f& p) {
    const double z = depth(p);
    return options.residual_base + options.residual_z2 * z * z;
  };

  std::map<int, std::vector<std::uint32_t>> members;
  for (std::uint32_t i = 0; i < cloud.size(); ++i)
    if (segments[i] > 0 && is_finite(cloud.xyz[i])) members[segments[i]].push_back(i);
  const std::vector<std::pair<int, std::vector<std::uint32_t>>> segment_list(members.begin(),
                                                                             members.end());
  std::vector<fit::SegmentPoints> points(segment_list.size());
  truth.objects.resize(segment_list.size());
  // One object an iteration (dynamic: objects differ in size); each fit has its own seed, so the
  // thread count changes nothing.
  detail::parallel_for(std::ptrdiff_t(segment_list.size()), context.threads,
                       detail::Schedule::Dynamic(1), [&](std::ptrdiff_t k) {
                         if (context.stop.stop_requested()) return;
                         const auto& [segment, indices] = segment_list[std::size_t(k)];
                         fit::SegmentPoints& s = points[std::size_t(k)];
                         s.viewpoint = t * origin;
                         for (auto i : indices) {
                           s.p.push_back(t * cloud.xyz[i].cast<double>());
                           s.n.push_back(t.linear() * work.normals[i].cast<double>());
                           s.bound.push_back(bound(cloud.xyz[i]));
                           s.depth.push_back(depth(cloud.xyz[i]));
                         }
                         truth.objects[std::size_t(k)] = choose_model(segment, s, options);
                       });
  context.throw_if_stopped("fitting the objects' shapes");
  reject_nested(truth.objects, points);

  // The fitted scene: the table slab (top face z = 0, far wider than any view) and the shapes.
  synth::Scene scene;
  Eigen::Isometry3d slab = Eigen::Isometry3d::Identity();
  slab.translate(Vec3d(0, 0, -0.04));
  scene.objects.emplace_back(std::make_shared<synth::BoxShape>(Vec3d(20, 20, 0.04)), slab, 0xC8A67A,
                             false);
  std::vector<fit::RulePoint> rule_points;
  std::vector<std::uint32_t> rule_index;  // cloud index of each rule point
  for (std::uint32_t i = 0; i < cloud.size(); ++i) {
    if (segments[i] != 0 || !is_finite(cloud.xyz[i])) continue;
    const Vec3d p = t * cloud.xyz[i].cast<double>();
    if (std::abs(p.z()) >= bound(cloud.xyz[i])) continue;
    rule_points.push_back({0, 5, Vec3d(p.x(), p.y(), 0.0)});  // part 5: the slab's top face
    rule_index.push_back(i);
  }
  std::size_t k = 0;
  for (const auto& [segment, indices] : members) {
    const FittedObject& object = truth.objects[k];
    const fit::SegmentPoints& s = points[k++];
    if (object.kind == FittedKind::kUnfitted) continue;
    scene.objects.emplace_back(fit::make_shape(object), object.table_from_local, 0x808080,
                               object.on_table);
    const int index = static_cast<int>(scene.objects.size()) - 1;
    const Eigen::Isometry3d local_from_table = object.table_from_local.inverse();
    for (std::size_t j = 0; j < indices.size(); ++j) {
      const fit::SurfacePoint sp = fit::closest_surface(object, local_from_table * s.p[j],
                                                        local_from_table.linear() * s.n[j]);
      if (sp.distance >= s.bound[j]) continue;
      rule_points.push_back({index, sp.part, object.table_from_local * sp.point});
      rule_index.push_back(indices[j]);
    }
  }
  const std::vector<std::uint32_t> labels =
      fit::label_by_rule(scene, rule_points, options.label_radius);
  for (std::size_t j = 0; j < labels.size(); ++j) truth.labels[rule_index[j]] = labels[j];
  return truth;
}

}  // namespace primlabel::synth
