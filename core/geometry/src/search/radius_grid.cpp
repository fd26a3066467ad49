#include "radius_grid.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace primlabel::detail {

std::unique_ptr<RadiusGrid> RadiusGrid::build(const FinitePoints& points, float radius,
                                              const std::stop_token& stop, bool& stopped) {
  stopped = false;
  if (points.size() == 0 || !(radius > 0.0f)) return nullptr;
  // Each serial pass below is cut into chunks of 64k points (~1 ms) with a stop check between.
  constexpr std::size_t kCheckEvery = std::size_t(1) << 16;
  const auto stop_at = [&](std::size_t i) {
    if (i % kCheckEvery == 0 && stop.stop_requested()) stopped = true;
    return stopped;
  };
  const std::size_t n = points.size();
  Vec3f lo = points[0], hi = points[0];
  for (std::size_t i = 0; i < n; ++i) {
    if (stop_at(i)) return nullptr;
    lo = lo.cwiseMin(points[i]), hi = hi.cwiseMax(points[i]);
  }
  // Cell counts in double: a far point (up to FLT_MAX) makes the float extent infinite and its
  // cell count overflow int64. Such clouds are left to the k-d tree.
  if (!std::isfinite(1.0f / radius)) return nullptr;
  const double max_cells = std::min(4.0 * double(n) + 4096, double(1 << 28));
  std::int64_t dims[3];
  double cells = 1;
  for (int d = 0; d < 3; ++d) {
    const double extent = (double(hi[d]) - double(lo[d])) / double(radius);
    if (!(extent < max_cells)) return nullptr;  // also NaN
    // The float quotient whenever it is finite: the same cells, so the same order.
    const float quotient = (hi[d] - lo[d]) / radius;
    const double span = std::isfinite(quotient) ? std::floor(quotient) : std::floor(extent);
    dims[d] = static_cast<std::int64_t>(std::min(span, max_cells)) + 1;
    cells *= double(dims[d]);
  }
  if (cells > max_cells) return nullptr;

  auto grid = std::unique_ptr<RadiusGrid>(new RadiusGrid);
  grid->origin_ = lo;
  grid->inv_cell_ = 1.0f / radius;
  for (int d = 0; d < 3; ++d) grid->dims_[d] = dims[d];
  std::vector<std::uint32_t> cell_of(n);
  grid->starts_.assign(static_cast<std::size_t>(cells) + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (stop_at(i)) return nullptr;
    cell_of[i] = static_cast<std::uint32_t>(grid->cell_index(grid->cell_coords(points[i])));
    ++grid->starts_[cell_of[i] + 1];
  }
  std::partial_sum(grid->starts_.begin(), grid->starts_.end(), grid->starts_.begin());
  grid->index_.resize(n);
  grid->points_.resize(n);
  std::vector<std::size_t> fill(grid->starts_.begin(), grid->starts_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {  // stable: points keep their cloud order within a cell
    if (stop_at(i)) return nullptr;
    const std::size_t slot = fill[cell_of[i]]++;
    grid->index_[slot] = points.cloud_index(i);
    grid->points_[slot] = points[i];
  }
  return grid;
}

bool RadiusGrid::cell_range(const Vec3f& q, float radius, std::int64_t lo[3],
                            std::int64_t hi[3]) const {
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::max<std::int64_t>(0, cell_coord(q[d] - radius, d));
    hi[d] = std::min<std::int64_t>(dims_[d] - 1, cell_coord(q[d] + radius, d));
    if (lo[d] > hi[d]) return false;
  }
  return true;
}

std::size_t RadiusGrid::candidates(const Vec3f& q, float radius) const {
  std::int64_t lo[3], hi[3];
  if (!cell_range(q, radius, lo, hi)) return 0;
  return candidates_in(lo, hi);
}

std::size_t RadiusGrid::candidates_in(const std::int64_t lo[3], const std::int64_t hi[3]) const {
  std::size_t total = 0;
  for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
    for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
      total += starts_[cell_index({hi[0], y, z}) + 1] - starts_[cell_index({lo[0], y, z})];
  return total;
}

// Clamped to [-1, dims] before the conversion: a query far outside the grid (or one whose float
// offset overflows) must not convert an out-of-range or NaN value to an integer.
std::int64_t RadiusGrid::cell_coord(float v, int d) const {
  const float c = std::floor((v - origin_[d]) * inv_cell_);
  if (!(c >= -1.0f)) return -1;
  if (!(c <= float(dims_[d]))) return dims_[d];
  return static_cast<std::int64_t>(c);
}

std::array<std::int64_t, 3> RadiusGrid::cell_coords(const Vec3f& p) const {
  return {std::clamp<std::int64_t>(cell_coord(p.x(), 0), 0, dims_[0] - 1),
          std::clamp<std::int64_t>(cell_coord(p.y(), 1), 0, dims_[1] - 1),
          std::clamp<std::int64_t>(cell_coord(p.z(), 2), 0, dims_[2] - 1)};
}

}  // namespace primlabel::detail
