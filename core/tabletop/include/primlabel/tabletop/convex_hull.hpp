#pragma once
// Point-in-hull tests and plane bases, for the table boundary in the table plane's own
// coordinates; the hull itself is primlabel::convex_hull (geometry/convex_hull.hpp).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "primlabel/geometry/convex_hull.hpp"

namespace primlabel::tabletop {

using Vec2f = Eigen::Vector2f;

// True when p lies inside the CCW convex polygon or within `margin` outside any of its edges
// (a negative margin shrinks the polygon). A polygon with fewer than 3 vertices contains nothing.
bool hull_contains(const std::vector<Vec2f>& hull, const Vec2f& p, float margin = 0.0f);

// Orthonormal basis (u, v) of the plane with normal n, so that (u, v, n) is right-handed.
void plane_basis(const Eigen::Vector3f& normal, Eigen::Vector3f& u, Eigen::Vector3f& v);

}  // namespace primlabel::tabletop
