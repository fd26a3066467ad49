#pragma once
// 2D convex hulls and the smallest rectangle around a point set: the table boundary of the
// table-top stage, the drawn extent of a fitted plane.

#include <Eigen/Core>
#include <vector>

namespace primlabel {

// Vertices of the convex hull in counter-clockwise order, no collinear or duplicate vertices.
// Fewer than three distinct non-collinear points give the (possibly degenerate) chain found.
std::vector<Eigen::Vector2f> convex_hull(std::vector<Eigen::Vector2f> points);

// A rectangle in the plane: centre, unit direction of its longer side, side lengths.
struct Rectangle2 {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  Eigen::Vector2d axis_u = Eigen::Vector2d::UnitX();  // along `length`
  double length = 0;                                  // >= width
  double width = 0;
};

// The minimum-area rectangle enclosing a convex polygon (a convex_hull result): one side lies
// on a hull edge (Freeman and Shapira), so each edge's direction is tried. An empty hull gives
// a zero rectangle; one or two points a rectangle of width 0.
Rectangle2 min_area_rectangle(const std::vector<Eigen::Vector2f>& hull);

}  // namespace primlabel
