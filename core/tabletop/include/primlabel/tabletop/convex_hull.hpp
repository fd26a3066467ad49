#pragma once
// 2D convex hull (Andrew's monotone chain) and point-in-hull tests, for the table boundary in the
// table plane's own coordinates.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace primlabel::tabletop {

using Vec2f = Eigen::Vector2f;

// Vertices of the convex hull in counter-clockwise order, no collinear or duplicate vertices.
// Fewer than three distinct non-collinear points give the (possibly degenerate) chain found.
std::vector<Vec2f> convex_hull(std::vector<Vec2f> points);

// True when p lies inside the CCW convex polygon or within `margin` outside any of its edges
// (a negative margin shrinks the polygon). A polygon with fewer than 3 vertices contains nothing.
bool hull_contains(const std::vector<Vec2f>& hull, const Vec2f& p, float margin = 0.0f);

// Orthonormal basis (u, v) of the plane with normal n, so that (u, v, n) is right-handed.
void plane_basis(const Eigen::Vector3f& normal, Eigen::Vector3f& u, Eigen::Vector3f& v);

}  // namespace primlabel::tabletop
