#pragma once
// Fixed-radius queries on dense scans return hundreds of points; walking the k-d tree for them
// costs more than scanning the few grid cells that can hold them. Cells are as wide as the
// radius and ordered x-fastest, so the <= 3 cells along x of each (y, z) row are one contiguous
// run: at most 9 runs per query. The grid keeps the points and their cloud indices in cell order.
// Distances are computed in nanoflann's order, so a grid query returns exactly the set the k-d tree
// would.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
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

  // How many points a query of this radius would compare (its <= 9 runs), without reading them.
  std::size_t candidates(const Vec3f& q, float radius) const;

  // Appends the points strictly within `radius` (sq_radius = radius^2) whose cloud index passes
  // `accept`, cell by cell, in cloud order within a cell.
  template <class Accept>
  void find(const Vec3f& q, float sq_radius, float radius, const Accept& accept,
            NeighborList& out) const {
    std::int64_t lo[3], hi[3];
    if (!cell_range(q, radius, lo, hi)) return;
    // Every candidate is written branch-free and kept if inside, so the writes need room for all
    // candidates: a per-thread buffer that is never zero-filled (growing the lists for each run
    // zero-filled every candidate, ~10% of a dense query).
    thread_local CandidateBuffer buffer;
    buffer.reserve(candidates_in(lo, hi));
    std::uint32_t* indices = buffer.indices.get();
    float* sq_dists = buffer.sq_dists.get();
    std::size_t count = 0;
    for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
        const std::size_t first = starts_[cell_index({lo[0], y, z})];
        const std::size_t last = starts_[cell_index({hi[0], y, z}) + 1];
        for (std::size_t i = first; i < last; ++i) {
          const std::uint32_t index = index_[i];
          const Vec3f& p = points_[i];
          // nanoflann's L2_Simple_Adaptor: ((0 + dx^2) + dy^2) + dz^2.
          const float dx = q.x() - p.x(), dy = q.y() - p.y(), dz = q.z() - p.z();
          const float sq = (dx * dx + dy * dy) + dz * dz;
          indices[count] = index;
          sq_dists[count] = sq;
          count += (sq < sq_radius) & accept(index);  // branch-free: write always, keep if inside
        }
      }
    out.indices.insert(out.indices.end(), indices, indices + count);
    out.sq_dists.insert(out.sq_dists.end(), sq_dists, sq_dists + count);
  }

 private:
  RadiusGrid() = default;
  // The cells a query of this radius reads, as [lo, hi] per axis; false when there are none.
  bool cell_range(const Vec3f& q, float radius, std::int64_t lo[3], std::int64_t hi[3]) const;
  std::size_t candidates_in(const std::int64_t lo[3], const std::int64_t hi[3]) const;
  std::int64_t cell_coord(float v, int d) const;

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
  float inv_cell_ = 1.0f;
  std::int64_t dims_[3] = {1, 1, 1};
  std::vector<std::size_t> starts_;   // per cell, into index_; one extra at the end
  std::vector<std::uint32_t> index_;  // cloud index of each grid slot, in cell order
};

}  // namespace primlabel::detail
