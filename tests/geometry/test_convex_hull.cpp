// The minimum-area rectangle around a convex hull: exact for rotated rectangles, the known
// optimum for a triangle, and the degenerate inputs (no point, one point, a segment).

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "primlabel/geometry/convex_hull.hpp"

namespace primlabel {
namespace {

using Eigen::Vector2d;
using Eigen::Vector2f;

// Points filling a w x h rectangle turned by `angle` about `center`, denser along a diagonal so
// their principal axes are not the rectangle's.
std::vector<Vector2f> rectangle_points(double w, double h, double angle, Vector2d center) {
  const Vector2d u(std::cos(angle), std::sin(angle)), v(-u.y(), u.x());
  std::vector<Vector2f> points;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j)
      points.push_back(
          (center + (i / 40.0 - 0.5) * w * u + (j / 40.0 - 0.5) * h * v).cast<float>());
  for (int i = 0; i <= 400; ++i) {
    const double t = i / 400.0 - 0.5;
    points.push_back((center + t * w * u + t * h * v).cast<float>());
  }
  return points;
}

TEST(MinAreaRectangle, FindsARotatedRectangleExactly) {
  for (double angle : {0.0, 0.3, 0.7854, 1.2, 2.5}) {
    const Vector2d center(1.5, -0.4);
    const Rectangle2 box =
        min_area_rectangle(convex_hull(rectangle_points(0.6, 0.5, angle, center)));
    EXPECT_NEAR(box.length, 0.6, 1e-5) << angle;
    EXPECT_NEAR(box.width, 0.5, 1e-5) << angle;
    EXPECT_LT((box.center - center).norm(), 1e-5) << angle;
    // The longer side's direction, up to sign.
    EXPECT_NEAR(std::abs(box.axis_u.dot(Vector2d(std::cos(angle), std::sin(angle)))), 1.0, 1e-6)
        << angle;
    EXPECT_NEAR(box.axis_u.norm(), 1.0, 1e-12);
  }
}

TEST(MinAreaRectangle, ATrianglesRectangleLiesOnAnEdge) {
  // Right triangle with legs 3 and 4: the best rectangle is 3 x 4 (area 12), on a leg.
  const Rectangle2 box = min_area_rectangle(convex_hull({{0, 0}, {4, 0}, {0, 3}}));
  EXPECT_NEAR(box.length * box.width, 12.0, 1e-5);
  EXPECT_NEAR(box.length, 4.0, 1e-5);
}

TEST(MinAreaRectangle, DegenerateHulls) {
  EXPECT_EQ(min_area_rectangle({}).length, 0.0);
  const Rectangle2 point = min_area_rectangle({{2, 3}});
  EXPECT_EQ(point.length, 0.0);
  EXPECT_EQ(point.center, Vector2d(2, 3));
  const Rectangle2 segment = min_area_rectangle(convex_hull({{0, 0}, {3, 4}}));
  EXPECT_NEAR(segment.length, 5.0, 1e-6);
  EXPECT_NEAR(segment.width, 0.0, 1e-6);
  EXPECT_LT((segment.center - Vector2d(1.5, 2)).norm(), 1e-6);
}

}  // namespace
}  // namespace primlabel
