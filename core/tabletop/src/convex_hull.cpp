#include "primlabel/tabletop/convex_hull.hpp"

#include <algorithm>
#include <cmath>

namespace primlabel::tabletop {

namespace {

// > 0 when o -> a -> b turns left, in double (metres apart, millimetres off a line).
double cross(const Vec2f& o, const Vec2f& a, const Vec2f& b) {
  return (double(a.x()) - o.x()) * (double(b.y()) - o.y()) -
         (double(a.y()) - o.y()) * (double(b.x()) - o.x());
}

}  // namespace

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

HullMembership::HullMembership(const std::vector<Vec2f>& hull, float margin, float cell)
    : hull_(hull), margin_(margin), cell_(cell) {}

bool HullMembership::contains(const Vec2f& p) {
  constexpr float kRoundingGuard = 1e-4f;
  const float sx = std::floor(p.x() / cell_), sy = std::floor(p.y() / cell_);
  if (std::isfinite(sx) && std::isfinite(sy) && std::abs(sx) < 2e9f && std::abs(sy) < 2e9f) {
    const auto x = static_cast<std::int32_t>(sx), y = static_cast<std::int32_t>(sy);
    const std::uint64_t key = std::uint64_t(std::uint32_t(x)) << 32 | std::uint32_t(y);
    auto [it, fresh] = square_inside_.try_emplace(key, false);
    if (fresh) {
      bool inside = true;
      for (int corner = 0; corner < 4 && inside; ++corner)
        inside = hull_contains(
            hull_, Vec2f((sx + float(corner & 1)) * cell_, (sy + float(corner >> 1)) * cell_),
            margin_ - kRoundingGuard);
      it->second = inside;
    }
    if (it->second) return true;
  }
  return hull_contains(hull_, p, margin_);
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
