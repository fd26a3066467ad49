#pragma once
// A fitted primitive instance: one connected segment of same-class points and the parametric
// model its class calls for (docs/tools.md: Primitive instances). Lengths in metres, directions unit.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <variant>

namespace primlabel::primitives {

using Vec3d = Eigen::Vector3d;

// Infinite plane n.x + offset = 0, and the oriented rectangle its inliers cover: centred on
// `center`, spanning extent_u along axis_u and extent_v along axis_v (extent_u >= extent_v).
struct PlaneModel {
  Vec3d normal = Vec3d::UnitZ();
  double offset = 0;
  Vec3d center = Vec3d::Zero();
  Vec3d axis_u = Vec3d::UnitX(), axis_v = Vec3d::UnitY();
  double extent_u = 0, extent_v = 0;
};

// Finite cylinder: the axis through `center` (the middle of the inliers' extent along it),
// `height` long. Convex and concave cylinders (a can, the inside of a mug) share the model.
struct CylinderModel {
  Vec3d center = Vec3d::Zero();
  Vec3d axis = Vec3d::UnitZ();
  double radius = 0;
  double height = 0;
};

struct SphereModel {
  Vec3d center = Vec3d::Zero();
  double radius = 0;
};

// Ring torus: the tube's centre circle of radius major_radius around `axis` through `center`.
struct TorusModel {
  Vec3d center = Vec3d::Zero();
  Vec3d axis = Vec3d::UnitZ();
  double major_radius = 0;
  double minor_radius = 0;
};

// Line segment from center - length/2 * direction to center + length/2 * direction.
struct LineModel {
  Vec3d center = Vec3d::Zero();
  Vec3d direction = Vec3d::UnitX();
  double length = 0;
};

// monostate: no parametric model (corners, classes without one, or a fit that failed).
using Model =
    std::variant<std::monostate, PlaneModel, CylinderModel, SphereModel, TorusModel, LineModel>;

// The variant's alternatives in order; numbers are part of the API (labeling.proto).
enum class PrimitiveKind : std::uint32_t {
  kSegment = 0,
  kPlane = 1,
  kCylinder = 2,
  kSphere = 3,
  kTorus = 4,
  kLine = 5,
};

PrimitiveKind kind_of(const Model& model);
// "segment", "plane", "cylinder", "sphere", "torus", "line".
std::string_view kind_name(PrimitiveKind kind);
std::optional<PrimitiveKind> kind_from_name(std::string_view name);

// The model a class is fitted with: plane for plane, cylinder for both cylinder classes, sphere
// for both sphere classes, torus for both torus classes, line for both edge classes, and
// kSegment (centroid and bounds only) for corners and ids outside the taxonomy.
PrimitiveKind model_for_class(std::uint32_t class_id);

struct Primitive {
  std::uint32_t class_id = 0;  // taxonomy class of the segment's points
  Model model;
  std::size_t points = 0;         // in the segment
  std::uint32_t first_point = 0;  // the segment's lowest point index
  Vec3d centroid = Vec3d::Zero();
  Vec3d bounds_min = Vec3d::Zero(), bounds_max = Vec3d::Zero();  // axis-aligned
  std::size_t inliers = 0;  // segment points within the distance threshold (and normal angle)
  double rms = 0;           // of the inliers' distances to the model (m)
  // In [0, 1]: inlier share times the model's coverage (cylinder, torus: the arc seen around the
  // axis over a half turn; sphere: the cap's half-angle over 90 degrees; plane, line: 1). 0 for
  // kSegment.
  double confidence = 0;

  PrimitiveKind kind() const { return kind_of(model); }
};

}  // namespace primlabel::primitives
