#pragma once
// What both scanners do with a return: label it, colour it, store it.

#include <cmath>
#include <cstdint>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/synth/ground_truth.hpp"
#include "primlabel/synth/scene.hpp"

namespace primlabel::synth::detail {

struct Return {
  Vec3f xyz = Vec3f::Constant(NAN);
  std::uint32_t label = 0;
  std::uint32_t rgba = 0;
  float object = -1;
  // For the observability pass: where the ray really hit, on which part, and that part's own
  // class (what the label falls back to when no crease is seen).
  Vec3f surface_xyz = Vec3f::Constant(NAN);
  int part = -1;
  std::uint32_t surface_label = 0;
};

inline Return make_return(const Scene& scene, const SceneHit& hit, const Vec3d& true_point,
                          const Vec3d& measured_point, double label_radius) {
  Return r;
  r.xyz = measured_point.cast<float>();
  r.label = class_id(ground_truth(scene, hit.object, hit.part, true_point, label_radius));
  r.surface_xyz = true_point.cast<float>();
  r.part = hit.part;
  const SceneObject& owner = scene.objects[hit.object];
  r.surface_label =
      class_id(owner.shape->surface_class(hit.part, owner.local_from_world * true_point));
  // Lambert shading from a light above and in front of the table makes rgb renders readable.
  const Vec3d light = Vec3d(0.3, -0.5, 1.0).normalized();
  const double shade = 0.45 + 0.55 * std::max(0.0, hit.normal.dot(light));
  const std::uint32_t rgb = scene.objects[hit.object].rgb;
  auto channel = [&](int shift) {
    return static_cast<std::uint32_t>(std::lround(double((rgb >> shift) & 0xFF) * shade)) << shift;
  };
  r.rgba = 0xFF000000u | channel(16) | channel(8) | channel(0);
  r.object = static_cast<float>(hit.object);
  return r;
}

// A crease or rim label says that the descriptor's support (radius r) straddles two surfaces. When
// the scan holds (almost) no points of the other surface within r - it faces away from the
// sensor, is seen at grazing incidence or lies in shadow - no descriptor can see that crease, so
// the point keeps the class of its own surface. "Almost none": fewer than
// kObservedCreaseFraction of the scanned points within r lie on another (object, part).
inline constexpr double kObservedCreaseFraction = 0.05;
void label_unseen_creases_as_surface(std::vector<Return>& returns, double label_radius);

inline void store_returns(const std::vector<Return>& returns, PointCloud& cloud) {
  cloud.xyz.resize(returns.size());
  cloud.labels.resize(returns.size());
  cloud.rgba.resize(returns.size());
  FloatField& object = cloud.set_field("object", 1);
  for (std::size_t i = 0; i < returns.size(); ++i) {
    cloud.xyz[i] = returns[i].xyz;
    cloud.labels[i] = returns[i].label;
    cloud.rgba[i] = returns[i].rgba;
    object.values[i] = returns[i].object;
  }
}

// `position` moved as SensorPlacement says: its (back, up) offset from the table's front edge
// (the line y = front, z = 0) scaled and turned about the edge.
inline Vec3d place_sensor(const Vec3d& position, double front, double range_scale,
                          double elevation_deg) {
  if (range_scale == 1.0 && elevation_deg == 0.0) return position;  // bit-identical default
  const double back = front - position.y(), up = position.z();
  const double length = range_scale * std::hypot(back, up);
  const double angle = std::atan2(up, back) + elevation_deg * M_PI / 180.0;
  return Vec3d(position.x(), front - length * std::cos(angle), length * std::sin(angle));
}

// Orientation whose z axis is `forward`, x axis horizontal to the right and y axis down (the
// usual camera convention, as PCL's sensor frames).
inline Eigen::Matrix3d camera_rotation(const Vec3d& forward) {
  const Vec3d z = forward.normalized();
  Vec3d x = z.cross(Vec3d::UnitZ());
  if (x.norm() < 1e-9) x = Vec3d::UnitX();
  x.normalize();
  const Vec3d y = z.cross(x);
  Eigen::Matrix3d rotation;
  rotation.col(0) = x;
  rotation.col(1) = y;
  rotation.col(2) = z;
  return rotation;
}

}  // namespace primlabel::synth::detail
