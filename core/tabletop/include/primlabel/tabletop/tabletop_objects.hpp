#pragma once
// The table-top stage's answer as instances, per scan: the table (its plane, hull and point
// count) and one TabletopObject per object cluster (points, centroid, axis-aligned bounds, height
// above the table and, when primitives were fitted, the primitive segments lying in it), with
// every point's object id. docs/service.md: Primitives and table-top objects.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/tabletop/tabletop.hpp"

namespace primlabel::tabletop {

// Per-point object ids: 0 the table, k object k (objects[k - 1]), kNoObject neither.
inline constexpr std::uint32_t kTableObject = 0;
inline constexpr std::uint32_t kNoObject = 0xFFFFFFFFu;

struct TabletopTable {
  Eigen::Vector4f plane = Eigen::Vector4f::Zero();  // n.p + d = 0, n = the up side
  std::vector<Vec3f> hull;                          // boundary on the plane, CCW about n
  std::size_t points = 0;
  std::vector<std::uint32_t> primitive_ids;  // segments mostly on the table, ascending
};

struct TabletopObject {
  std::uint32_t id = 0;  // >= 1: its per-point id
  std::size_t points = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d bounds_min = Eigen::Vector3d::Zero(), bounds_max = Eigen::Vector3d::Zero();
  double height = 0;  // of its highest point above the table plane (m)
  // Primitive segments more than half of whose points lie in this object, ascending.
  std::vector<std::uint32_t> primitive_ids;
};

struct TabletopObjects {
  std::optional<TabletopTable> table;       // none when no table was found (then no objects)
  std::string message;                      // why not, when there is no table
  std::vector<TabletopObject> objects;      // objects[k - 1] has id k: largest first
  std::vector<std::uint32_t> point_object;  // per point: kTableObject, k or kNoObject
};

// The ids of segment_tabletop's result for a cloud of `num_points` points, with the table's plane
// and hull; the counts and shapes are left to describe_objects (after any fan-out of the ids).
TabletopObjects object_ids(const TabletopResult& result, std::size_t num_points);

// Fills the table's point count and every object from `objects.point_object` and the points'
// coordinates (one per id), then renumbers the objects largest first by those points (ties keep
// their order), in `point_object` too; an id without points still gets its (empty) object, last,
// so ids and indices agree.
void describe_objects(const std::vector<Vec3f>& xyz, TabletopObjects& objects);

// Gives the table and every object the ids of the primitive segments more than half of whose
// points carry its id. `point_segment` holds one segment id per point (kNoSegment = 0xFFFFFFFF:
// none), `segment_points` the size of every segment.
void assign_primitives(std::span<const std::uint32_t> point_segment,
                       std::span<const std::size_t> segment_points, TabletopObjects& objects);

}  // namespace primlabel::tabletop
