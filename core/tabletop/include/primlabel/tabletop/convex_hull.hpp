#pragma once
// Point-in-hull tests and plane bases, for the table boundary in the table plane's own
// coordinates; the hull itself is primlabel::convex_hull (geometry/convex_hull.hpp).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "primlabel/geometry/convex_hull.hpp"

namespace primlabel::tabletop {

using Vec2f = Eigen::Vector2f;

// True when p lies inside the CCW convex polygon or within `margin` outside any of its edges
// (a negative margin shrinks the polygon). A polygon with fewer than 3 vertices contains nothing.
bool hull_contains(const std::vector<Vec2f>& hull, const Vec2f& p, float margin = 0.0f);

// hull_contains for the many points of a scan: the region is convex, so a square of edge `cell`
// whose four corners lie inside it (by a further 0.1 mm, against rounding) holds only inside
// points, and most points are answered by one lookup of their square. The same answers as
// hull_contains.
class HullMembership {
 public:
  HullMembership(const std::vector<Vec2f>& hull, float margin, float cell);
  bool contains(const Vec2f& p);

 private:
  const std::vector<Vec2f>& hull_;  // must outlive this
  float margin_, cell_;
  std::unordered_map<std::uint64_t, bool> square_inside_;
};

// Orthonormal basis (u, v) of the plane with normal n, so that (u, v, n) is right-handed.
void plane_basis(const Eigen::Vector3f& normal, Eigen::Vector3f& u, Eigen::Vector3f& v);

}  // namespace primlabel::tabletop
