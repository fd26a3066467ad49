#pragma once
// A synthetic table for the table-top object tests: a 0.8 m table top at z = 0 and, standing
// `lift` above it (0: on it), two boxes and a can, sampled on a regular grid every `spacing`
// metres, with their true labels (plane; the can's side cylinder) and outward normals. The
// sensor is upright above (its -y is +z), so every up-axis source finds the table.

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel::testing {

struct ObjectsScene {
  PointCloud cloud;                   // with the true normals
  std::vector<std::uint32_t> labels;  // true taxonomy class per point
  std::vector<std::uint32_t> object;  // 0 table, 1 box A, 2 box B, 3 can (input order)
  Eigen::Vector3d lo[4], hi[4];       // true axis-aligned bounds of each part
  static constexpr double kCanRadius = 0.04;
};

inline ObjectsScene objects_scene(float spacing = 0.005f, float lift = 0.0f) {
  ObjectsScene scene;
  std::vector<Vec3f> xyz, normals;
  const auto add = [&](double x, double y, double z, const Vec3f& n, PrimitiveClass c,
                       std::uint32_t part) {
    xyz.emplace_back(float(x), float(y), float(z));
    normals.push_back(n);
    scene.labels.push_back(class_id(c));
    scene.object.push_back(part);
  };
  const int table_steps = int(std::lround(0.8 / spacing));
  for (int i = 0; i <= table_steps; ++i)
    for (int j = 0; j <= table_steps; ++j)
      add(-0.4 + i * spacing, -0.4 + j * spacing, 0.0, Vec3f::UnitZ(), PrimitiveClass::kPlane, 0);
  scene.lo[0] = {-0.4, -0.4, 0.0};
  scene.hi[0] = {-0.4 + table_steps * spacing, -0.4 + table_steps * spacing, 0.0};
  // A box of corner (x0, y0), sizes (sx, sy, sz): four sides and the top.
  const auto box = [&](double x0, double y0, double sx, double sy, double sz, std::uint32_t part) {
    const double z0 = lift;
    const int nx = int(std::lround(sx / spacing)), ny = int(std::lround(sy / spacing)),
              nz = int(std::lround(sz / spacing));
    for (int i = 0; i <= nx; ++i)
      for (int k = 0; k <= nz; ++k) {
        add(x0 + i * spacing, y0, z0 + k * spacing, -Vec3f::UnitY(), PrimitiveClass::kPlane, part);
        add(x0 + i * spacing, y0 + sy, z0 + k * spacing, Vec3f::UnitY(), PrimitiveClass::kPlane,
            part);
      }
    for (int j = 1; j < ny; ++j)
      for (int k = 0; k <= nz; ++k) {
        add(x0, y0 + j * spacing, z0 + k * spacing, -Vec3f::UnitX(), PrimitiveClass::kPlane, part);
        add(x0 + sx, y0 + j * spacing, z0 + k * spacing, Vec3f::UnitX(), PrimitiveClass::kPlane,
            part);
      }
    for (int i = 1; i < nx; ++i)
      for (int j = 1; j < ny; ++j)
        add(x0 + i * spacing, y0 + j * spacing, z0 + sz, Vec3f::UnitZ(), PrimitiveClass::kPlane,
            part);
    scene.lo[part] = {x0, y0, z0};
    scene.hi[part] = {x0 + nx * spacing, y0 + ny * spacing, z0 + nz * spacing};
  };
  box(-0.30, -0.30, 0.12, 0.12, 0.10, 1);
  box(0.10, -0.30, 0.16, 0.10, 0.06, 2);
  // The can: its side (convex cylinder) and its lid (plane).
  const double r = ObjectsScene::kCanRadius, height = 0.12, cx = 0.0, cy = 0.2;
  const int around = int(std::lround(2 * M_PI * r / spacing));
  const int up = int(std::lround(height / spacing));
  for (int a = 0; a < around; ++a) {
    const double angle = 2 * M_PI * a / around;
    const Vec3f n(float(std::cos(angle)), float(std::sin(angle)), 0.0f);
    for (int k = 0; k <= up; ++k)
      add(cx + r * n.x(), cy + r * n.y(), lift + k * spacing, n, PrimitiveClass::kCylinderConvex,
          3);
  }
  for (double x = -r + spacing; x < r; x += spacing)
    for (double y = -r + spacing; y < r; y += spacing)
      if (x * x + y * y < (r - spacing) * (r - spacing))
        add(cx + x, cy + y, lift + up * spacing, Vec3f::UnitZ(), PrimitiveClass::kPlane, 3);
  scene.lo[3] = {cx - r, cy - r, lift};
  scene.hi[3] = {cx + r, cy + r, lift + up * spacing};
  // Points on the table under an object are not seen: drop them (the object's own stay).
  std::vector<Vec3f> kept_xyz, kept_normals;
  std::vector<std::uint32_t> kept_labels, kept_object;
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    bool hidden = false;
    if (scene.object[i] == 0)
      for (int part = 1; part <= 3; ++part)
        hidden = hidden || (xyz[i].x() >= scene.lo[part].x() && xyz[i].x() <= scene.hi[part].x() &&
                            xyz[i].y() >= scene.lo[part].y() && xyz[i].y() <= scene.hi[part].y());
    if (hidden) continue;
    kept_xyz.push_back(xyz[i]);
    kept_normals.push_back(normals[i]);
    kept_labels.push_back(scene.labels[i]);
    kept_object.push_back(scene.object[i]);
  }
  scene.labels = std::move(kept_labels);
  scene.object = std::move(kept_object);
  scene.cloud.resize_unorganized(kept_xyz.size());
  scene.cloud.xyz = std::move(kept_xyz);
  scene.cloud.normals = std::move(kept_normals);
  scene.cloud.viewpoint.origin = Vec3f(0.0f, -0.6f, 1.2f);
  scene.cloud.viewpoint.orientation = Eigen::AngleAxisf(-float(M_PI) / 2, Vec3f::UnitX());
  return scene;
}

// The scene as a camera sees it, with an identity orientation: x right, y down, z forward (the
// table's up is -y), as a scan reaches the service (ScanHeader carries no orientation).
inline PointCloud in_camera_frame(const ObjectsScene& scene) {
  const Eigen::Matrix3f rotation = Eigen::AngleAxisf(float(M_PI) / 2, Vec3f::UnitX()).matrix();
  PointCloud cloud = scene.cloud;
  for (Vec3f& p : cloud.xyz) p = rotation * p;
  for (Vec3f& n : cloud.normals) n = rotation * n;
  cloud.viewpoint.origin = rotation * cloud.viewpoint.origin;
  cloud.viewpoint.orientation = Eigen::Quaternionf::Identity();
  return cloud;
}

}  // namespace primlabel::testing
