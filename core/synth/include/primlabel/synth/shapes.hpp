#pragma once
// The solid objects of synthetic scenes, each in its own frame: z up, standing on the plane z = 0
// (the table's top face for objects), centred on the z axis. Every shape answers three questions
// exactly, from its analytic surfaces: where a ray first hits it (and on which part), what
// primitive a part is, and which feature curves (edges, rims) lie near a point - the ground truth
// at a scale is built from these (ground_truth.hpp).

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string_view>
#include <vector>

#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel::synth {

using Vec3d = Eigen::Vector3d;

struct Ray {
  Vec3d origin;
  Vec3d dir;  // unit length
  Vec3d at(double t) const { return origin + t * dir; }
};

struct SurfaceHit {
  double t = std::numeric_limits<double>::infinity();
  int part = -1;                 // index into the shape's parts
  Vec3d normal = Vec3d::Zero();  // unit, pointing out of the material
};

// A curve of the surface that changes the class of points within the label radius of it.
struct Feature {
  enum class Kind {
    kConvexEdge,   // sharp convex crease (box edge, can lid)
    kConcaveEdge,  // sharp concave crease (mug inner floor meets wall)
    kRim,          // the rounded lip of an open vessel: points near it are torus-convex
  };
  enum class Geometry { kSegment, kCircle };

  Kind kind = Kind::kConvexEdge;
  Geometry geometry = Geometry::kSegment;
  Vec3d a = Vec3d::Zero();    // segment start, or circle centre
  Vec3d b = Vec3d::Zero();    // segment end, or circle axis (unit)
  double radius = 0;          // circle radius
  std::uint32_t parts = ~0u;  // bit i set: applies to points on part i

  static Feature segment(Kind kind, const Vec3d& from, const Vec3d& to, std::uint32_t parts = ~0u);
  static Feature circle(Kind kind, const Vec3d& centre, const Vec3d& axis, double radius,
                        std::uint32_t parts = ~0u);
  double distance(const Vec3d& p) const;
};

class Shape {
 public:
  virtual ~Shape() = default;

  virtual std::string_view kind() const = 0;

  // First hit with t in (t_min, t_max), the ray in the shape's frame.
  virtual bool intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const = 0;

  // The primitive a point p of `part` lies on, before features and contacts are considered.
  virtual PrimitiveClass surface_class(int part, const Vec3d& p) const = 0;

  // False for parts inside a vessel (a mug's inner wall and floor): they never touch the table.
  virtual bool exterior(int part) const { return true; }

  // Distance from a point outside the solid to the solid (0 inside); may underestimate far away.
  virtual double distance_outside(const Vec3d& p) const = 0;

  // How far a point of an exterior part is inside the shape's footprint on z = 0 (0 outside or
  // on its rim): the point's distance to the exposed support is hypot(z, footprint_inset).
  virtual double footprint_inset(const Vec3d& p) const { return 0.0; }

  // Radius of a vertical cylinder around the z axis that contains the shape (for placement).
  virtual double footprint_radius() const = 0;

  const std::vector<Feature>& features() const { return features_; }
  const Vec3d& bound_center() const { return bound_center_; }
  double bound_radius() const { return bound_radius_; }

 protected:
  std::vector<Feature> features_;
  Vec3d bound_center_ = Vec3d::Zero();
  double bound_radius_ = 0;
};

// Axis-aligned box [-sx/2, sx/2] x [-sy/2, sy/2] x [0, sz]. Parts 0..5: faces -x, +x, -y, +y,
// -z, +z. Every face is a plane; the top and vertical edges are convex features, the bottom ones
// only when `bottom_edges` (a free-standing box seen from below); a box on a table has contact
// creases there instead (ground_truth.hpp).
class BoxShape : public Shape {
 public:
  BoxShape(const Vec3d& size, bool bottom_edges = false);
  std::string_view kind() const override { return "box"; }
  bool intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const override;
  PrimitiveClass surface_class(int, const Vec3d&) const override { return PrimitiveClass::kPlane; }
  double distance_outside(const Vec3d& p) const override;
  double footprint_inset(const Vec3d& p) const override;
  double footprint_radius() const override { return 0.5 * std::hypot(size_.x(), size_.y()); }
  const Vec3d& size() const { return size_; }

 private:
  Vec3d size_, lo_, hi_;
};

// Closed cylinder (a can): parts 0 side (convex cylinder), 1 lid (plane), 2 bottom (plane). The
// lid's circular edge is a convex edge.
class CanShape : public Shape {
 public:
  CanShape(double radius, double height);
  std::string_view kind() const override { return "can"; }
  bool intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const override;
  PrimitiveClass surface_class(int part, const Vec3d&) const override;
  double distance_outside(const Vec3d& p) const override;
  double footprint_inset(const Vec3d& p) const override;
  double footprint_radius() const override { return radius_; }
  double radius() const { return radius_; }
  double height() const { return height_; }

 private:
  double radius_, height_;
};

// Closed cylinder lying on its side (a can or a roll on the table): axis along x, length
// [-length/2, length/2], touching z = 0 along the line y = 0. Parts: 0 side (convex cylinder),
// 1 cap at +x, 2 cap at -x (planes); both cap circles are convex edges. Its footprint on z = 0 is
// a line, so every side point within r of the table is at the contact crease, as for a ball.
class LyingCanShape : public Shape {
 public:
  LyingCanShape(double radius, double length);
  std::string_view kind() const override { return "lying-can"; }
  bool intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const override;
  PrimitiveClass surface_class(int part, const Vec3d&) const override;
  double distance_outside(const Vec3d& p) const override;
  double footprint_radius() const override { return std::hypot(radius_, 0.5 * length_); }
  // The upright frame of the same can (axis z, bottom cap at z = 0, the -x cap) from this frame.
  Vec3d upright_from_local(const Vec3d& p) const {
    return Vec3d(p.z() - radius_, p.y(), p.x() + 0.5 * length_);
  }
  Vec3d local_from_upright(const Vec3d& q) const {
    return Vec3d(q.z() - 0.5 * length_, q.y(), q.x() + radius_);
  }
  double radius() const { return radius_; }
  double length() const { return length_; }

 private:
  double radius_, length_;
  CanShape upright_;
};

// Open vessel with a wall and a floor (a mug; a cup without the handle). Parts: 0 outer wall
// (convex cylinder), 1 inner wall (concave cylinder), 2 lip (the flat annulus on top), 3 inner
// floor (plane), 4 bottom, 5 handle (a torus arc, torus-convex: at the label scale a thin ring).
// Features: the rim (lip circle) and the concave crease where the inner wall meets the floor.
class MugShape : public Shape {
 public:
  struct Handle {
    double major_radius = 0;  // 0: no handle
    double tube_radius = 0;
    double height = 0;  // of the ring's centre above the bottom
    double offset = 0;  // ring centre beyond the outer wall
  };
  MugShape(double radius, double height, double wall, double floor, const Handle& handle);
  std::string_view kind() const override { return handle_.major_radius > 0 ? "mug" : "cup"; }
  bool intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const override;
  PrimitiveClass surface_class(int part, const Vec3d&) const override;
  bool exterior(int part) const override { return part != 1 && part != 3; }
  double distance_outside(const Vec3d& p) const override;
  double footprint_inset(const Vec3d& p) const override;
  double footprint_radius() const override;
  double outer_radius() const { return radius_; }
  double inner_radius() const { return inner_radius_; }
  double height() const { return height_; }
  double floor_height() const { return floor_; }  // of the inner floor above the bottom

 private:
  bool intersect_handle(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const;
  double radius_, height_, inner_radius_, floor_;
  Handle handle_;
  Vec3d handle_center_;
};

// Bowl: a spherical shell cut flat at the bottom (a foot of radius `foot` on z = 0) and at the
// rim height. Parts: 0 outer sphere (sphere-convex), 1 inner sphere (sphere-concave), 2 lip,
// 3 bottom. Feature: the rim.
class BowlShape : public Shape {
 public:
  // rim_drop: how far the rim lies below the sphere's equator (0 = hemisphere).
  BowlShape(double radius, double rim_drop);
  std::string_view kind() const override { return "bowl"; }
  bool intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const override;
  PrimitiveClass surface_class(int part, const Vec3d&) const override;
  bool exterior(int part) const override { return part != 1; }
  double distance_outside(const Vec3d& p) const override;
  double footprint_inset(const Vec3d& p) const override;
  double footprint_radius() const override { return outer_rim_radius_max_; }
  double rim_height() const { return rim_z_; }
  // The two spheres' radii and their common centre's height above the table.
  double outer_radius() const { return radius_; }
  double inner_radius() const { return inner_radius_; }
  double center_height() const { return center_z_; }

 private:
  double radius_, inner_radius_, center_z_, rim_z_, foot_;
  double inner_rim_radius_, outer_rim_radius_, outer_rim_radius_max_;
};

// Ball resting on z = 0: sphere-convex everywhere.
class BallShape : public Shape {
 public:
  explicit BallShape(double radius);
  std::string_view kind() const override { return "ball"; }
  bool intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const override;
  PrimitiveClass surface_class(int, const Vec3d&) const override {
    return PrimitiveClass::kSphereConvex;
  }
  double distance_outside(const Vec3d& p) const override;
  double footprint_radius() const override { return radius_; }
  double radius() const { return radius_; }

 private:
  double radius_;
};

// Ring lying flat on z = 0 (a donut, a tape roll with round edges): torus-convex on its outer
// side (farther from the axis than the tube's centre circle), torus-concave around the hole.
class TorusShape : public Shape {
 public:
  TorusShape(double major_radius, double tube_radius);
  std::string_view kind() const override { return "torus"; }
  bool intersect(const Ray& ray, double t_min, double t_max, SurfaceHit& hit) const override;
  PrimitiveClass surface_class(int, const Vec3d& p) const override;
  double distance_outside(const Vec3d& p) const override;
  double footprint_radius() const override { return major_ + tube_; }
  double major_radius() const { return major_; }
  double tube_radius() const { return tube_; }

 private:
  double major_, tube_;
};

}  // namespace primlabel::synth
