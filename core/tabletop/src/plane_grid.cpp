#include "primlabel/tabletop/plane_grid.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "disjoint_sets.hpp"

namespace primlabel::tabletop {

namespace {

std::uint64_t pack(std::int32_t x, std::int32_t y) {
  return (std::uint64_t(std::uint32_t(y)) << 32) | std::uint32_t(x);
}

std::size_t hash_slot(std::uint64_t key, std::size_t slots) {
  return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 17) & (slots - 1);
}

// 2D cross product of (a - o) and (b - o), in double: see convex_hull.cpp.
double cross(const Vec2f& o, const Vec2f& a, const Vec2f& b) {
  return (double(a.x()) - o.x()) * (double(b.y()) - o.y()) -
         (double(a.y()) - o.y()) * (double(b.x()) - o.x());
}

}  // namespace

PlaneGrid::PlaneGrid(const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& indices,
                     const Eigen::Vector4f& plane, float cell)
    : points_(points), indices_(indices), cell_(cell), cell_of_point_(points.size(), UINT32_MAX) {
  if (!(cell > 0.0f) || !std::isfinite(cell))
    throw std::invalid_argument("plane grid cell must be positive, got " + std::to_string(cell));
  if (!std::is_sorted(indices_.begin(), indices_.end()))
    std::sort(indices_.begin(), indices_.end());
  normal_ = plane.head<3>().normalized();
  plane_basis(normal_, u_, v_);
  origin_ = Eigen::Vector3d::Zero();
  if (!indices_.empty()) origin_ = points[indices_[0]].cast<double>();

  std::size_t slots = 64;
  while (slots < 2 * indices_.size()) slots *= 2;
  hash_.assign(slots, UINT32_MAX);
  const double inv = 1.0 / cell;
  constexpr double kLimit = 2.0e9;  // integer cell coordinates must fit in int32
  std::uint64_t last_key = 0;
  std::uint32_t last_cell = UINT32_MAX;
  for (std::uint32_t i : indices_) {
    const Vec2f q = project(points[i]);
    const double fx = std::floor(q.x() * inv), fy = std::floor(q.y() * inv);
    if (!(std::abs(fx) < kLimit && std::abs(fy) < kLimit))
      throw std::invalid_argument("plane grid: a point is too far away for cells of " +
                                  std::to_string(cell) + " m");
    const auto x = static_cast<std::int32_t>(fx), y = static_cast<std::int32_t>(fy);
    const std::uint64_t key = pack(x, y);
    if (key != last_key || last_cell == UINT32_MAX) {  // neighbours in a scan share cells
      std::size_t slot = hash_slot(key, slots);
      while (hash_[slot] != UINT32_MAX && pack(cells_[hash_[slot]].x, cells_[hash_[slot]].y) != key)
        slot = (slot + 1) & (slots - 1);
      if (hash_[slot] == UINT32_MAX) {
        hash_[slot] = static_cast<std::uint32_t>(cells_.size());
        cells_.push_back(Cell{x, y, 0, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()});
      }
      last_key = key;
      last_cell = hash_[slot];
    }
    Cell& c = cells_[last_cell];
    const Eigen::Vector3d d = points[i].cast<double>() - origin_;
    ++c.count;
    c.sum += d;
    c.products.noalias() += d * d.transpose();
    cell_of_point_[i] = last_cell;
  }
}

std::int64_t PlaneGrid::find(std::int32_t x, std::int32_t y) const {
  const std::uint64_t key = pack(x, y);
  for (std::size_t slot = hash_slot(key, hash_.size());; slot = (slot + 1) & (hash_.size() - 1)) {
    if (hash_[slot] == UINT32_MAX) return -1;
    const Cell& c = cells_[hash_[slot]];
    if (c.x == x && c.y == y) return hash_[slot];
  }
}

std::vector<std::vector<std::uint32_t>> PlaneGrid::connected_parts() const {
  DisjointSets sets(cells_.size());
  for (std::uint32_t a = 0; a < cells_.size(); ++a) {
    // Half of the 8-neighbourhood: every adjacent pair is visited once.
    constexpr int kOffsets[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
    for (const auto& o : kOffsets) {
      const std::int64_t b = find(cells_[a].x + o[0], cells_[a].y + o[1]);
      if (b >= 0) sets.join(a, static_cast<std::uint32_t>(b));
    }
  }
  std::vector<std::uint32_t> part_of_root(cells_.size(), UINT32_MAX);
  std::vector<std::vector<std::uint32_t>> parts;
  for (std::uint32_t i : indices_) {  // ascending, so every part is too
    const std::uint32_t root = sets.find(cell_of_point_[i]);
    if (part_of_root[root] == UINT32_MAX) {
      part_of_root[root] = static_cast<std::uint32_t>(parts.size());
      parts.emplace_back();
    }
    parts[part_of_root[root]].push_back(i);
  }
  std::stable_sort(parts.begin(), parts.end(),
                   [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return parts;
}

double PlaneGrid::fraction_parallel(const std::vector<std::uint32_t>& subset,
                                    float max_angle_deg) const {
  // One verdict per cell (its 3x3 neighbourhood), computed when first needed.
  enum : std::uint8_t { kUnknown, kParallel, kOblique, kSparse };
  std::vector<std::uint8_t> verdict(cells_.size(), kUnknown);
  const double min_cos = std::cos(double(max_angle_deg) * M_PI / 180.0);
  std::size_t counted = 0, parallel = 0;
  for (std::uint32_t i : subset) {
    const std::uint32_t c = i < cell_of_point_.size() ? cell_of_point_[i] : UINT32_MAX;
    if (c == UINT32_MAX) continue;
    if (verdict[c] == kUnknown) {
      std::uint64_t count = 0;
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      Eigen::Matrix3d products = Eigen::Matrix3d::Zero();
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const std::int64_t n = find(cells_[c].x + dx, cells_[c].y + dy);
          if (n < 0) continue;
          count += cells_[n].count;
          sum += cells_[n].sum;
          products += cells_[n].products;
        }
      if (count < 6) {
        verdict[c] = kSparse;
      } else {
        const Eigen::Vector3d mean = sum / double(count);
        const Eigen::Matrix3d covariance = products / double(count) - mean * mean.transpose();
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
        solver.computeDirect(covariance);
        const double alignment = std::abs(solver.eigenvectors().col(0).dot(normal_.cast<double>()));
        verdict[c] = alignment >= min_cos ? kParallel : kOblique;
      }
    }
    if (verdict[c] == kSparse) continue;
    ++counted;
    parallel += verdict[c] == kParallel;
  }
  return counted ? double(parallel) / double(counted) : 0.0;
}

std::vector<Vec2f> PlaneGrid::hull_candidates(const std::vector<std::uint32_t>& subset) const {
  std::vector<std::uint8_t> holds(cells_.size(), 0);
  for (std::uint32_t i : subset) holds[cell_of_point_[i]] = 1;
  // A cell whose four diagonal neighbours hold points lies inside the quadrilateral of any four
  // of those points (each lies beyond one of its corners), so its points are not hull vertices.
  std::vector<std::uint8_t> interior(cells_.size(), 0);
  for (std::uint32_t c = 0; c < cells_.size(); ++c) {
    if (!holds[c]) continue;
    bool surrounded = true;
    for (const auto& [dx, dy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
      const std::int64_t n = find(cells_[c].x + dx, cells_[c].y + dy);
      if (n < 0 || !holds[n]) {
        surrounded = false;
        break;
      }
    }
    interior[c] = surrounded;
  }
  std::vector<Vec2f> candidates;
  for (std::uint32_t i : subset)
    if (!interior[cell_of_point_[i]]) candidates.push_back(project(points_[i]));
  return candidates;
}

std::vector<std::uint64_t> PlaneGrid::footprint(const std::vector<Vec3f>& points,
                                                const std::vector<std::uint32_t>& indices,
                                                int grow) const {
  std::vector<std::uint64_t> keys;
  keys.reserve(indices.size());
  for (std::uint32_t i : indices) {
    const Vec2f q = project(points[i]);
    keys.push_back(pack(static_cast<std::int32_t>(std::floor(q.x() / cell_)),
                        static_cast<std::int32_t>(std::floor(q.y() / cell_))));
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  if (grow <= 0) return keys;
  std::vector<std::uint64_t> grown;
  grown.reserve(keys.size() * std::size_t(2 * grow + 1) * std::size_t(2 * grow + 1));
  for (std::uint64_t key : keys) {
    const auto x = static_cast<std::int32_t>(std::uint32_t(key)),
               y = static_cast<std::int32_t>(std::uint32_t(key >> 32));
    for (int dy = -grow; dy <= grow; ++dy)
      for (int dx = -grow; dx <= grow; ++dx) grown.push_back(pack(x + dx, y + dy));
  }
  std::sort(grown.begin(), grown.end());
  grown.erase(std::unique(grown.begin(), grown.end()), grown.end());
  return grown;
}

std::size_t PlaneGrid::count_inside(const std::vector<Vec2f>& polygon, float margin,
                                    const std::vector<std::uint64_t>& excluded) const {
  if (polygon.size() < 3) return 0;
  Vec2f lo = polygon[0], hi = polygon[0];
  for (const Vec2f& p : polygon) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const auto inside = [&](const Vec2f& p) {
    for (std::size_t k = 0, n = polygon.size(); k < n; ++k) {
      const Vec2f& a = polygon[k];
      const Vec2f& b = polygon[(k + 1) % n];
      const double length = (b - a).norm();
      if (length > 0 && cross(a, b, p) / length < double(margin)) return false;
    }
    return true;
  };
  const auto counted = [&](const Cell& c) {
    return !std::binary_search(excluded.begin(), excluded.end(), pack(c.x, c.y)) &&
           inside(Vec2f((c.x + 0.5f) * cell_, (c.y + 0.5f) * cell_));
  };
  std::size_t total = 0;
  const auto x0 = static_cast<std::int32_t>(std::floor(lo.x() / cell_));
  const auto x1 = static_cast<std::int32_t>(std::floor(hi.x() / cell_));
  const auto y0 = static_cast<std::int32_t>(std::floor(lo.y() / cell_));
  const auto y1 = static_cast<std::int32_t>(std::floor(hi.y() / cell_));
  const std::int64_t area = (std::int64_t(x1) - x0 + 1) * (std::int64_t(y1) - y0 + 1);
  if (area <= std::int64_t(cells_.size())) {  // walk the polygon's cells
    for (std::int32_t y = y0; y <= y1; ++y)
      for (std::int32_t x = x0; x <= x1; ++x) {
        const std::int64_t c = find(x, y);
        if (c >= 0 && counted(cells_[c])) total += cells_[c].count;
      }
  } else {  // fewer occupied cells than the polygon covers: walk those
    for (const Cell& c : cells_)
      if (c.x >= x0 && c.x <= x1 && c.y >= y0 && c.y <= y1 && counted(c)) total += c.count;
  }
  return total;
}

}  // namespace primlabel::tabletop
