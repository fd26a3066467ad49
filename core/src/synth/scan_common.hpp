#pragma once
// What both scanners do with a return: label it, colour it, store it.

#include <cstdint>

#include "primlabel/core/point_cloud.hpp"
#include "primlabel/synth/ground_truth.hpp"
#include "primlabel/synth/scene.hpp"

namespace primlabel::synth::detail {

struct Return {
  Vec3f xyz = Vec3f::Constant(NAN);
  std::uint32_t label = 0;
  std::uint32_t rgba = 0;
  float object = -1;
};

inline Return make_return(const Scene& scene, const SceneHit& hit, const Vec3d& true_point,
                          const Vec3d& measured_point, double label_radius) {
  Return r;
  r.xyz = measured_point.cast<float>();
  r.label = class_id(ground_truth(scene, hit.object, hit.part, true_point, label_radius));
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
