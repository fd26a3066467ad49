#pragma once
// Fixed-radius queries on dense scans return hundreds of points; walking the k-d tree for them
// costs more than scanning the few grid cells that can hold them. Cells are half
// of the radius wide where the cloud's extent allows, and ordered x-fastest, so the cells along x
// of each (y, z) row are one contiguous run; a query skips the rows that lie wholly outside its
// sphere and reads of the others only the x-span the sphere covers (far fewer candidates than
// radius-wide cells). The grid keeps the points and their cloud indices in cell
// order. Distances are computed in nanoflann's order, so a grid query returns exactly the set the
// k-d tree would.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <stop_token>
#include <vector>

#include "finite_points.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::detail {

class RadiusGrid {
 public:
  // Returns nullptr when the cloud is too sparse for a grid of this cell size to pay off, and
  // sets `stopped` (and returns nullptr) when `stop` is requested during the build. `points`
  // must outlive the grid.
  static std::unique_ptr<RadiusGrid> build(const FinitePoints& points, float radius,
                                           const std::stop_token& stop, bool& stopped);

  // Appends the points strictly within `radius` (sq_radius = radius^2) whose cloud index passes
  // `accept`, cell by cell, in cloud order within a cell.
  // Returns false, and appends nothing, when the query would compare more than
  // `max_candidates` points.
  template <class Accept>
  bool find(const Vec3f& q, float sq_radius, float radius, const Accept& accept, NeighborList& out,
            std::size_t max_candidates = std::numeric_limits<std::size_t>::max()) const {
    // Every candidate is written branch-free and kept if inside, so the writes need room for all
    // candidates: a per-thread buffer that is never zero-filled (growing the lists for each run
    // zero-filled every candidate, a visible share of a dense query).
    thread_local CandidateBuffer buffer;
    thread_local std::vector<Run> runs;
    const std::size_t candidates = query_runs(q, radius, runs);
    if (candidates > max_candidates) return false;
    buffer.reserve(candidates);
    std::uint32_t* indices = buffer.indices.get();
    float* sq_dists = buffer.sq_dists.get();
    std::size_t count = 0;
    for (const Run& run : runs)
      for (std::size_t i = run.first; i < run.last; ++i) {
        const std::uint32_t index = index_[i];
        const Vec3f& p = points_[i];
        // nanoflann's L2_Simple_Adaptor: ((0 + dx^2) + dy^2) + dz^2.
        const float dx = q.x() - p.x(), dy = q.y() - p.y(), dz = q.z() - p.z();
        const float sq = (dx * dx + dy * dy) + dz * dz;
        indices[count] = index;
        sq_dists[count] = sq;
        count += (sq < sq_radius) & accept(index);  // branch-free: write always, keep if inside
      }
    out.indices.insert(out.indices.end(), indices, indices + count);
    out.sq_dists.insert(out.sq_dists.end(), sq_dists, sq_dists + count);
    return true;
  }

 private:
  RadiusGrid() = default;
  // A contiguous slice of the grid's slots: one (y, z) row's cells that the sphere can reach.
  struct Run {
    std::size_t first, last;
  };
  // The runs a query of this radius reads, in cell order, into `runs`; their total length.
  std::size_t query_runs(const Vec3f& q, float radius, std::vector<Run>& runs) const;
  // Clamped to [-1, dims] before the conversion: a query far outside the grid (or one whose
  // float offset overflows) must not convert an out-of-range or NaN value to an integer. Inline:
  // a query computes a few dozen of these.
  std::int64_t cell_coord(float v, int d) const {
    const float c = std::floor((v - origin_[d]) * inv_cell_);
    if (!(c >= -1.0f)) return -1;
    if (!(c <= float(dims_[d]))) return dims_[d];
    return static_cast<std::int64_t>(c);
  }

  // Room for one query's candidates, grown (never shrunk or initialised) as queries need it.
  struct CandidateBuffer {
    std::unique_ptr<std::uint32_t[]> indices;
    std::unique_ptr<float[]> sq_dists;
    std::size_t capacity = 0;
    void reserve(std::size_t wanted) {
      if (wanted <= capacity) return;
      capacity = std::max(wanted, 2 * capacity);
      indices.reset(new std::uint32_t[capacity]);
      sq_dists.reset(new float[capacity]);
    }
  };
  std::array<std::int64_t, 3> cell_coords(const Vec3f& p) const;
  std::size_t cell_index(const std::array<std::int64_t, 3>& c) const {
    return static_cast<std::size_t>((c[2] * dims_[1] + c[1]) * dims_[0] + c[0]);
  }

  // The points in cell order: a query reads its runs contiguously instead of gathering them
  // from the cloud (12 bytes a point; the gathers were most of a dense query's time).
  std::vector<Vec3f> points_;
  Vec3f origin_;
  float cell_ = 1.0f;
  float inv_cell_ = 1.0f;
  std::int64_t dims_[3] = {1, 1, 1};
  std::vector<std::size_t> starts_;   // per cell, into index_; one extra at the end
  std::vector<std::uint32_t> index_;  // cloud index of each grid slot, in cell order
};

}  // namespace primlabel::detail
