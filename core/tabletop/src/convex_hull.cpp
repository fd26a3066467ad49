#include "primlabel/tabletop/convex_hull.hpp"

#include <algorithm>
#include <cmath>

namespace primlabel::tabletop {

namespace {

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

bool hull_contains(const std::vector<Vec2f>& hull, const Vec2f& p, float margin) {
  if (hull.size() < 3) return false;
  for (std::size_t i = 0, n = hull.size(); i < n; ++i) {
    const Vec2f& a = hull[i];
    const Vec2f& b = hull[(i + 1) % n];
    const Vec2f edge = b - a;
    const float length = edge.norm();
    if (length == 0.0f) continue;
    // Signed distance of p to the left of the edge (inside for a CCW polygon).
    const double inside = cross(a, b, p) / length;
    if (inside < -double(margin)) return false;
  }
  return true;
}

void plane_basis(const Eigen::Vector3f& normal, Eigen::Vector3f& u, Eigen::Vector3f& v) {
  const Eigen::Vector3f n = normal.normalized();
  // Start from the coordinate axis least aligned with n, for a well-conditioned cross product.
  int least = 0;
  n.cwiseAbs().minCoeff(&least);
  const Eigen::Vector3f seed = Eigen::Vector3f::Unit(least);
  u = seed.cross(n).normalized();
  v = n.cross(u);
}

}  // namespace primlabel::tabletop
