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
  // Half-radius cells where their count stays within max_cells, else radius-wide ones (thirds
  // saved no more instructions than halves on LMS400 and Kinect scans; callgrind):
  // finer cells fit a query's sphere more closely, but every cell costs a slot even when empty.
  std::int64_t dims[3];
  double cells = 0;
  float cell = radius;
  for (int parts = 2; parts >= 1; --parts) {
    cell = parts == 1 ? radius : radius / float(parts);
    if (!(cell > 0.0f) || !std::isfinite(1.0f / cell)) return nullptr;
    cells = 1;
    bool fits = true;
    for (int d = 0; d < 3 && fits; ++d) {
      const double extent = (double(hi[d]) - double(lo[d])) / double(cell);
      if (!(extent < max_cells)) {  // also NaN
        fits = false;
        break;
      }
      // The float quotient whenever it is finite: the same cells, so the same order.
      const float quotient = (hi[d] - lo[d]) / cell;
      const double span = std::isfinite(quotient) ? std::floor(quotient) : std::floor(extent);
      dims[d] = static_cast<std::int64_t>(std::min(span, max_cells)) + 1;
      cells *= double(dims[d]);
    }
    if (fits && cells <= max_cells) break;
    if (parts == 1) return nullptr;
  }

  auto grid = std::unique_ptr<RadiusGrid>(new RadiusGrid);
  grid->origin_ = lo;
  grid->cell_ = cell;
  grid->inv_cell_ = 1.0f / cell;
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

std::size_t RadiusGrid::query_runs(const Vec3f& q, float radius, std::vector<Run>& runs) const {
  runs.clear();
  std::int64_t lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::max<std::int64_t>(0, cell_coord(q[d] - radius, d));
    hi[d] = std::min<std::int64_t>(dims_[d] - 1, cell_coord(q[d] + radius, d));
    if (lo[d] > hi[d]) return 0;
  }
  // Rows and x-spans are culled against a slightly larger sphere: a point is filed under the
  // cell its rounded coordinate falls in, which may lie a rounding error outside the cell's
  // nominal bounds. The slack only adds candidates; the distance test decides.
  // Filing rounds (p - origin) * (1 / cell) in float: an error of a few ulps of the cell
  // coordinate (up to the largest dimension) and of the coordinates themselves.
  double scale = std::fabs(double(radius));
  for (int d = 0; d < 3; ++d)
    scale = std::max({scale, std::fabs(double(q[d])), std::fabs(double(origin_[d]))});
  const double widest = double(std::max({dims_[0], dims_[1], dims_[2]}));
  const double slack = double(cell_) * (1e-4 + 1e-6 * widest) + 1e-6 * scale;
  const double reach = double(radius) + slack;
  const double sq_reach = reach * reach;
  // The distance from the query to the slab of cell c along axis d (0 inside it).
  const auto square = [](double v) { return v * v; };
  const auto slab_distance = [&](std::int64_t c, int d) {
    const double low = double(origin_[d]) + double(c) * double(cell_);
    const double v = double(q[d]);
    if (v < low) return low - v;
    if (v > low + double(cell_)) return v - (low + double(cell_));
    return 0.0;
  };
  // Squared slab distances per row coordinate (a query spans at most a handful of cells).
  constexpr std::int64_t kMaxSpan = 16;
  double dz2[kMaxSpan], dy2[kMaxSpan];
  const std::int64_t z_count = std::min(hi[2] - lo[2] + 1, kMaxSpan);
  const std::int64_t y_count = std::min(hi[1] - lo[1] + 1, kMaxSpan);
  if (z_count < hi[2] - lo[2] + 1 || y_count < hi[1] - lo[1] + 1) {
    // Cells narrower than radius / 8 are never built; this is only a guard.
    for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
        runs.push_back(
            {starts_[cell_index({lo[0], y, z})], starts_[cell_index({hi[0], y, z}) + 1]});
  } else {
    for (std::int64_t k = 0; k < z_count; ++k) dz2[k] = square(slab_distance(lo[2] + k, 2));
    for (std::int64_t k = 0; k < y_count; ++k) dy2[k] = square(slab_distance(lo[1] + k, 1));
    for (std::int64_t kz = 0; kz < z_count; ++kz) {
      if (dz2[kz] > sq_reach) continue;
      const std::int64_t z = lo[2] + kz;
      for (std::int64_t ky = 0; ky < y_count; ++ky) {
        const double rest = sq_reach - dz2[kz] - dy2[ky];
        if (rest < 0.0) continue;
        const std::int64_t y = lo[1] + ky;
        const float half = static_cast<float>(std::sqrt(rest) + slack);
        const std::int64_t x0 = std::max(lo[0], cell_coord(q.x() - half, 0));
        const std::int64_t x1 = std::min(hi[0], cell_coord(q.x() + half, 0));
        if (x0 > x1) continue;
        const std::size_t row = cell_index({0, y, z});
        const std::size_t first = starts_[row + std::size_t(x0)];
        const std::size_t last = starts_[row + std::size_t(x1) + 1];
        if (first != last) runs.push_back({first, last});
      }
    }
  }
  std::size_t total = 0;
  for (const Run& run : runs) total += run.last - run.first;
  return total;
}

std::array<std::int64_t, 3> RadiusGrid::cell_coords(const Vec3f& p) const {
  return {std::clamp<std::int64_t>(cell_coord(p.x(), 0), 0, dims_[0] - 1),
          std::clamp<std::int64_t>(cell_coord(p.y(), 1), 0, dims_[1] - 1),
          std::clamp<std::int64_t>(cell_coord(p.z(), 2), 0, dims_[2] - 1)};
}

}  // namespace primlabel::detail
