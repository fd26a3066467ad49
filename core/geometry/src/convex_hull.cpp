#include "primlabel/geometry/convex_hull.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace primlabel {

namespace {

using Vec2f = Eigen::Vector2f;

// > 0 when o -> a -> b turns left. Double: hull points can be metres apart yet millimetres
// off a line.
double cross(const Vec2f& o, const Vec2f& a, const Vec2f& b) {
  return (double(a.x()) - o.x()) * (double(b.y()) - o.y()) -
         (double(a.y()) - o.y()) * (double(b.x()) - o.x());
}

// Akl-Toussaint: the points strictly inside the polygon of the extremes in eight directions
// cannot be hull vertices. Drops nearly all of a dense table before the sort.
void drop_interior_points(std::vector<Vec2f>& points) {
  if (points.size() < 64) return;
  const Eigen::Vector2f directions[8] = {{1, 0},  {1, 1},   {0, 1},  {-1, 1},
                                         {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
  Vec2f extreme[8];
  float best[8];
  for (int k = 0; k < 8; ++k) {
    extreme[k] = points[0];
    best[k] = directions[k].dot(points[0]);
  }
  for (const Vec2f& p : points)
    for (int k = 0; k < 8; ++k) {
      const float s = directions[k].dot(p);
      if (s > best[k]) {
        best[k] = s;
        extreme[k] = p;
      }
    }
  std::vector<Vec2f> polygon;  // CCW, directions are in angular order
  for (const Vec2f& e : extreme)
    if (polygon.empty() || (e != polygon.back() && e != polygon.front())) polygon.push_back(e);
  if (polygon.size() < 3) return;
  std::erase_if(points, [&](const Vec2f& p) {
    for (std::size_t i = 0; i < polygon.size(); ++i)
      if (cross(polygon[i], polygon[(i + 1) % polygon.size()], p) <= 0) return false;
    return true;
  });
}

}  // namespace

std::vector<Vec2f> convex_hull(std::vector<Vec2f> points) {
  drop_interior_points(points);
  std::sort(points.begin(), points.end(), [](const Vec2f& a, const Vec2f& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) return points;

  std::vector<Vec2f> hull(2 * points.size());
  std::size_t k = 0;
  for (const Vec2f& p : points) {  // lower chain
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0) --k;
    hull[k++] = p;
  }
  for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);  // the last point repeats the first
  return hull;
}

Rectangle2 min_area_rectangle(const std::vector<Vec2f>& hull) {
  Rectangle2 best;
  if (hull.empty()) return best;
  double best_area = std::numeric_limits<double>::infinity();
  // Each edge's direction (for one or two points, the first point to the second, or x).
  const std::size_t n = hull.size();
  for (std::size_t e = 0; e < std::max<std::size_t>(n, 1); ++e) {
    Eigen::Vector2d u = (hull[(e + 1) % n] - hull[e]).cast<double>();
    if (!(u.norm() > 0)) {
      if (n > 1) continue;
      u = Eigen::Vector2d::UnitX();
    }
    u.normalize();
    const Eigen::Vector2d v(-u.y(), u.x());
    double lo_u = INFINITY, hi_u = -INFINITY, lo_v = INFINITY, hi_v = -INFINITY;
    for (const Vec2f& p : hull) {
      const Eigen::Vector2d q = p.cast<double>();
      lo_u = std::min(lo_u, q.dot(u)), hi_u = std::max(hi_u, q.dot(u));
      lo_v = std::min(lo_v, q.dot(v)), hi_v = std::max(hi_v, q.dot(v));
    }
    const double area = (hi_u - lo_u) * (hi_v - lo_v);
    if (!(area < best_area) && best_area != INFINITY) continue;
    best_area = area;
    best.center = 0.5 * (lo_u + hi_u) * u + 0.5 * (lo_v + hi_v) * v;
    best.axis_u = u;
    best.length = hi_u - lo_u;
    best.width = hi_v - lo_v;
  }
  if (best.width > best.length) {
    std::swap(best.length, best.width);
    best.axis_u = Eigen::Vector2d(best.axis_u.y(), -best.axis_u.x());
  }
  return best;
}

}  // namespace primlabel
