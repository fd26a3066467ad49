#pragma once
// A synthetic table scene: a table slab whose top face is the plane z = 0 of the world frame,
// and objects on it, each a shape with a pose (a position on the table and a yaw; objects leaning
// on others are also tilted).
// Generation is deterministic for a seed.

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "primlabel/synth/shapes.hpp"

namespace primlabel::synth {

struct SceneObject {
  std::shared_ptr<const Shape> shape;
  Eigen::Isometry3d world_from_local = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d local_from_world = Eigen::Isometry3d::Identity();
  std::uint32_t rgb = 0x808080;        // base colour for the cloud's rgb field
  bool on_support = true;              // stands on the table (false for the table itself)
  Vec3d bound_center = Vec3d::Zero();  // world frame
  double bound_radius = 0;

  SceneObject(std::shared_ptr<const Shape> shape, const Eigen::Isometry3d& pose, std::uint32_t rgb,
              bool on_support);
};

struct SceneHit {
  double t = 0;
  int object = -1;  // index into Scene::objects; 0 is the table
  int part = -1;
  Vec3d normal = Vec3d::Zero();  // world frame, out of the material
};

struct Scene {
  std::vector<SceneObject> objects;  // objects[0] is the table (the support)
  Vec3d table_size = Vec3d::Zero();  // x, y extent and thickness of the slab

  // Nearest hit of a world-frame ray with t in (t_min, t_max).
  std::optional<SceneHit> cast(const Ray& ray, double t_min, double t_max) const;
  // True when something blocks the segment from `from` to `to` (shadow rays).
  bool occluded(const Vec3d& from, const Vec3d& to) const;
};

enum class SceneKind {
  kTable,       // a table with 4-8 randomly chosen, posed and sized kitchen objects
  kPrimitives,  // one of each shape in a row on a table, for tests and demos
  kEmptyTable,  // the bare table (noise statistics)
  // A crowded table for the table-top stage (not for labeling accuracy: touching objects share
  // creases the truth rule does not model): 8-14 objects a few millimetres apart, books lying
  // flat and boxes stacked on boxes. Each object, stacked ones included, is its own instance.
  kClutter,
  // The crowded table's hard cases on top of clutter's: 8-14 objects (stacked and leaning ones
  // included), some in contact (0-3 mm apart), a box on a box of nearly its footprint or a can on
  // a can, a book or flat box leaning against a box (tilted, resting on its edge), a can beside a
  // box of its height and colour. Each object is its own instance; for the table-top stage.
  kCrowded,
};

struct TableSceneOptions {
  int min_objects = 7;
  int max_objects = 10;
  double min_gap = 0.035;  // between object footprints: labels never mix two objects
};

Scene make_scene(SceneKind kind, std::uint64_t seed, const TableSceneOptions& options = {});

// The objects' kinds, e.g. "box,can,mug" (table excluded).
std::string describe_objects(const Scene& scene);

}  // namespace primlabel::synth
