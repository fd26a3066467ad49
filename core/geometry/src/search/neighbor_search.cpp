#include "primlabel/geometry/neighbor_search.hpp"

// Equal distances are reported lowest index first, so k-nearest lists are reproducible.
#define NANOFLANN_FIRST_MATCH
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <nanoflann.hpp>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "primlabel/geometry/cancellation.hpp"

namespace primlabel {

std::string Neighborhood::describe() const {
  std::ostringstream s;
  if (radius > 0.0f && max_neighbors > 0)
    s << "radius " << radius << " (at most " << max_neighbors << " neighbours)";
  else if (radius > 0.0f)
    s << "radius " << radius;
  else
    s << k << " nearest";
  return s.str();
}

namespace {

// nanoflann dataset adaptor over the compacted finite points.
struct CompactPoints {
  std::vector<Vec3f> points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][dim]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

using KdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, CompactPoints>,
                                        CompactPoints, 3, std::uint32_t>;

// Points per stop check in the serial loops over the whole cloud (~1 ms of work each).
constexpr std::size_t kCheckEvery = std::size_t(1) << 16;
// A capped radius query on a grid reads its cells only when they hold at most this many points
// per allowed neighbour (a sphere fills ~1/6 of the cells' box in 3D, ~1/3 on a surface).
constexpr std::size_t kCandidatesPerNeighbor = 8;
// Subtrees of at most this many points are built by nanoflann in one call (a few ms each).
constexpr std::size_t kCheckedSubtree = std::size_t(1) << 16;

// nanoflann's KDTreeBaseClass::divideTree for the nodes above kCheckedSubtree points, so the stop
// token can be checked between subtrees (a 5M-point build is one ~1 s call otherwise). Node
// allocation order, splits and the permutation of vAcc are exactly nanoflann's, so the tree and
// every query answer are the same as KdTree::buildIndex() gives.
KdTree::NodePtr divide_checked(KdTree& tree, std::size_t left, std::size_t right,
                               KdTree::BoundingBox& bbox, const std::stop_token& stop) {
  throw_if_stopped(stop, "building the neighbour index");
  if (right - left <= kCheckedSubtree) return tree.divideTree(tree, left, right, bbox);
  // right - left > leaf size: the non-leaf branch of divideTree.
  KdTree::NodePtr node = tree.pool.allocate<KdTree::Node>();
  KdTree::Offset idx;
  KdTree::Dimension cutfeat;
  KdTree::DistanceType cutval;
  tree.middleSplit_(tree, left, right - left, idx, cutfeat, cutval, bbox);
  node->node_type.sub.divfeat = cutfeat;
  KdTree::BoundingBox left_bbox(bbox);
  left_bbox[cutfeat].high = cutval;
  node->child1 = divide_checked(tree, left, left + idx, left_bbox, stop);
  KdTree::BoundingBox right_bbox(bbox);
  right_bbox[cutfeat].low = cutval;
  node->child2 = divide_checked(tree, left + idx, right, right_bbox, stop);
  node->node_type.sub.divlow = left_bbox[cutfeat].high;
  node->node_type.sub.divhigh = right_bbox[cutfeat].low;
  for (int i = 0; i < 3; ++i) {
    bbox[i].low = std::min(left_bbox[i].low, right_bbox[i].low);
    bbox[i].high = std::max(left_bbox[i].high, right_bbox[i].high);
  }
  return node;
}

// KdTree::buildIndex() with stop checks (the tree must have been made with
// SkipInitialBuildIndex).
void build_checked(KdTree& tree, const std::stop_token& stop) {
  static_assert(kCheckedSubtree > 16, "subtrees handed to nanoflann must not be leaves");
  tree.m_size = tree.dataset.kdtree_get_point_count();
  tree.m_size_at_index_build = tree.m_size;
  tree.init_vind();
  tree.freeIndex(tree);
  tree.m_size_at_index_build = tree.m_size;
  if (tree.m_size == 0) return;
  tree.computeBoundingBox(tree.root_bbox);
  tree.root_node = divide_checked(tree, 0, tree.m_size, tree.root_bbox, stop);
}

// Collects every point strictly inside the radius straight into the caller's NeighborList,
// translating compact indices back to cloud indices.
class RadiusCollector {
 public:
  RadiusCollector(float sq_radius, const std::vector<std::uint32_t>& to_cloud, NeighborList& out)
      : sq_radius_(sq_radius), to_cloud_(to_cloud), out_(out) {}
  std::size_t size() const { return out_.indices.size(); }
  bool full() const { return true; }
  float worstDist() const { return sq_radius_; }
  bool addPoint(float sq_dist, std::uint32_t compact_index) {
    if (sq_dist < sq_radius_) {
      out_.indices.push_back(to_cloud_[compact_index]);
      out_.sq_dists.push_back(sq_dist);
    }
    return true;
  }

 private:
  float sq_radius_;
  const std::vector<std::uint32_t>& to_cloud_;
  NeighborList& out_;
};

// Collects points strictly inside the radius like RadiusCollector, but gives up (and ends the
// search) once more than `limit` are found: a capped radius query then asks for the nearest
// instead, so a dense cluster costs O(limit), not O(cluster).
class BoundedRadiusCollector {
 public:
  BoundedRadiusCollector(float sq_radius, std::size_t limit,
                         const std::vector<std::uint32_t>& to_cloud, NeighborList& out)
      : sq_radius_(sq_radius), limit_(limit), to_cloud_(to_cloud), out_(out) {}
  std::size_t size() const { return out_.indices.size(); }
  bool full() const { return true; }
  float worstDist() const { return sq_radius_; }
  bool addPoint(float sq_dist, std::uint32_t compact_index) {
    if (!(sq_dist < sq_radius_)) return true;
    if (out_.indices.size() == limit_) {
      overflowed_ = true;
      return false;  // nanoflann stops the whole search
    }
    out_.indices.push_back(to_cloud_[compact_index]);
    out_.sq_dists.push_back(sq_dist);
    return true;
  }
  bool overflowed() const { return overflowed_; }

 private:
  float sq_radius_;
  std::size_t limit_;
  const std::vector<std::uint32_t>& to_cloud_;
  NeighborList& out_;
  bool overflowed_ = false;
};

// The `capacity` nearest points closer than `bound`, exactly the set nanoflann's KNNResultSet
// keeps (with NANOFLANN_FIRST_MATCH: ordered by distance, then index), but in a max-heap: an
// insertion costs O(log k), not O(k), so large caps stay cheap. Once full at distance 0 nothing
// can enter any more; worstDist() < 0 then prunes every remaining subtree, where nanoflann would
// visit every coincident point (N^2 for N duplicates).
class NearestSet {
 public:
  NearestSet(std::size_t capacity, float bound) : capacity_(capacity), bound_(bound) {
    heap_.reserve(capacity);
  }
  std::size_t size() const { return heap_.size(); }
  bool full() const { return heap_.size() == capacity_; }
  float worstDist() const {
    if (!full()) return bound_;
    const float worst = heap_.front().first;
    return worst > 0.0f ? worst : -1.0f;
  }
  bool addPoint(float sq_dist, std::uint32_t compact_index) {
    const Entry entry{sq_dist, compact_index};
    if (!full()) {
      heap_.push_back(entry);
      std::push_heap(heap_.begin(), heap_.end());
    } else if (entry < heap_.front()) {
      std::pop_heap(heap_.begin(), heap_.end());
      heap_.back() = entry;
      std::push_heap(heap_.begin(), heap_.end());
    }
    return true;
  }
  // Sorted by (distance, compact index), translated to cloud indices.
  void write(const std::vector<std::uint32_t>& to_cloud, NeighborList& out) {
    std::sort_heap(heap_.begin(), heap_.end());
    out.indices.resize(heap_.size());
    out.sq_dists.resize(heap_.size());
    for (std::size_t j = 0; j < heap_.size(); ++j) {
      out.sq_dists[j] = heap_[j].first;
      out.indices[j] = to_cloud[heap_[j].second];
    }
  }

 private:
  using Entry = std::pair<float, std::uint32_t>;
  std::size_t capacity_;
  float bound_;
  std::vector<Entry> heap_;
};

void sort_by_distance(NeighborList& list) {
  const std::size_t n = list.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    if (list.sq_dists[a] != list.sq_dists[b]) return list.sq_dists[a] < list.sq_dists[b];
    return list.indices[a] < list.indices[b];
  });
  NeighborList sorted;
  sorted.indices.reserve(n);
  sorted.sq_dists.reserve(n);
  for (std::uint32_t o : order) {
    sorted.indices.push_back(list.indices[o]);
    sorted.sq_dists.push_back(list.sq_dists[o]);
  }
  list.indices.swap(sorted.indices);
  list.sq_dists.swap(sorted.sq_dists);
}

}  // namespace

// Fixed-radius queries on dense scans return hundreds of points; walking the k-d tree for them
// costs more than scanning the few grid cells that can hold them. Cells are as wide as the
// radius and stored x-fastest, so the <= 3 cells along x of each (y, z) row are one contiguous
// run: at most 9 runs per query. Distances are computed in nanoflann's order, so a grid query
// returns exactly the set the tree would.
class RadiusGrid {
 public:
  // Returns nullptr when the cloud is too sparse for a grid of this cell size to pay off, and
  // sets `stopped` (and returns nullptr) when `stop` is requested during the build.
  static std::unique_ptr<RadiusGrid> build(const std::vector<Vec3f>& points,
                                           const std::vector<std::uint32_t>& to_cloud, float radius,
                                           const std::stop_token& stop, bool& stopped) {
    stopped = false;
    if (points.empty() || !(radius > 0.0f)) return nullptr;
    // Each serial pass below is cut into chunks of kCheckEvery points with a stop check between.
    const auto stop_at = [&](std::size_t i) {
      if (i % kCheckEvery == 0 && stop.stop_requested()) stopped = true;
      return stopped;
    };
    Vec3f lo = points[0], hi = points[0];
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (stop_at(i)) return nullptr;
      lo = lo.cwiseMin(points[i]), hi = hi.cwiseMax(points[i]);
    }
    // Cell counts in double: a far point (up to FLT_MAX) makes the float extent infinite and its
    // cell count overflow int64. Such clouds are left to the k-d tree.
    if (!std::isfinite(1.0f / radius)) return nullptr;
    const double max_cells = std::min(4.0 * double(points.size()) + 4096, double(1 << 28));
    std::int64_t dims[3];
    double cells = 1;
    for (int d = 0; d < 3; ++d) {
      const double extent = (double(hi[d]) - double(lo[d])) / double(radius);
      if (!(extent < max_cells)) return nullptr;  // also NaN
      // The float quotient, as before, whenever it is finite: the same cells, so the same order.
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
    const std::size_t n = points.size();
    std::vector<std::uint32_t> cell_of(n);
    grid->starts_.assign(static_cast<std::size_t>(cells) + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (stop_at(i)) return nullptr;
      cell_of[i] = static_cast<std::uint32_t>(grid->cell_index(grid->cell_coords(points[i])));
      ++grid->starts_[cell_of[i] + 1];
    }
    std::partial_sum(grid->starts_.begin(), grid->starts_.end(), grid->starts_.begin());
    grid->x_.resize(n), grid->y_.resize(n), grid->z_.resize(n), grid->index_.resize(n);
    std::vector<std::uint32_t> fill(grid->starts_.begin(), grid->starts_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {  // stable: points keep their order within a cell
      if (stop_at(i)) return nullptr;
      const std::uint32_t slot = fill[cell_of[i]]++;
      grid->x_[slot] = points[i].x(), grid->y_[slot] = points[i].y(),
      grid->z_[slot] = points[i].z();
      grid->index_[slot] = to_cloud[i];
    }
    return grid;
  }

  // The cells a query of this radius reads, as [lo, hi] per axis; false when there are none.
  bool cell_range(const Vec3f& q, float radius, std::int64_t lo[3], std::int64_t hi[3]) const {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::max<std::int64_t>(0, cell_coord(q[d] - radius, d));
      hi[d] = std::min<std::int64_t>(dims_[d] - 1, cell_coord(q[d] + radius, d));
      if (lo[d] > hi[d]) return false;
    }
    return true;
  }

  // How many points the query would compare (its <= 9 runs), without reading them.
  std::size_t candidates(const Vec3f& q, float radius) const {
    std::int64_t lo[3], hi[3];
    if (!cell_range(q, radius, lo, hi)) return 0;
    std::size_t total = 0;
    for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
        total += starts_[cell_index({hi[0], y, z}) + 1] - starts_[cell_index({lo[0], y, z})];
    return total;
  }

  void find(const Vec3f& q, float sq_radius, float radius, NeighborList& out) const {
    std::int64_t lo[3], hi[3];
    if (!cell_range(q, radius, lo, hi)) return;
    for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
        const std::size_t first = starts_[cell_index({lo[0], y, z})];
        const std::size_t last = starts_[cell_index({hi[0], y, z}) + 1];
        std::size_t count = out.indices.size();
        out.indices.resize(count + (last - first));
        out.sq_dists.resize(count + (last - first));
        for (std::size_t i = first; i < last; ++i) {
          // nanoflann's L2_Simple_Adaptor: ((0 + dx^2) + dy^2) + dz^2.
          const float dx = q.x() - x_[i], dy = q.y() - y_[i], dz = q.z() - z_[i];
          const float sq = (dx * dx + dy * dy) + dz * dz;
          out.indices[count] = index_[i];
          out.sq_dists[count] = sq;
          count += sq < sq_radius;  // branch-free: write always, keep if inside
        }
        out.indices.resize(count);
        out.sq_dists.resize(count);
      }
  }

  float radius() const { return 1.0f / inv_cell_; }

 private:
  RadiusGrid() = default;
  // Clamped to [-1, dims] before the conversion: a query far outside the grid (or one whose
  // float offset overflows) must not convert an out-of-range or NaN value to an integer.
  std::int64_t cell_coord(float v, int d) const {
    const float c = std::floor((v - origin_[d]) * inv_cell_);
    if (!(c >= -1.0f)) return -1;
    if (!(c <= float(dims_[d]))) return dims_[d];
    return static_cast<std::int64_t>(c);
  }
  std::array<std::int64_t, 3> cell_coords(const Vec3f& p) const {
    return {std::clamp<std::int64_t>(cell_coord(p.x(), 0), 0, dims_[0] - 1),
            std::clamp<std::int64_t>(cell_coord(p.y(), 1), 0, dims_[1] - 1),
            std::clamp<std::int64_t>(cell_coord(p.z(), 2), 0, dims_[2] - 1)};
  }
  std::size_t cell_index(const std::array<std::int64_t, 3>& c) const {
    return static_cast<std::size_t>((c[2] * dims_[1] + c[1]) * dims_[0] + c[0]);
  }

  Vec3f origin_;
  float inv_cell_ = 1.0f;
  std::int64_t dims_[3] = {1, 1, 1};
  std::vector<std::size_t> starts_;  // per cell, into the arrays below; one extra at the end
  std::vector<float> x_, y_, z_;
  std::vector<std::uint32_t> index_;  // cloud index of each grid slot
};

struct NeighborSearch::Impl {
  CompactPoints compact;
  std::vector<std::uint32_t> to_cloud;  // compact index -> cloud index
  std::unique_ptr<KdTree> tree;
  std::stop_token stop;  // cuts lazy grid builds short

  // Radius grids are built on first use for a radius and kept; a radius that does not suit a
  // grid is remembered as such (nullptr) so the tree answers it.
  std::mutex grids_mutex;
  std::vector<std::pair<float, std::unique_ptr<RadiusGrid>>> grids;

  const RadiusGrid* grid_for(float radius) {
    std::lock_guard<std::mutex> lock(grids_mutex);
    for (const auto& [r, grid] : grids)
      if (r == radius) return grid.get();
    bool stopped = false;
    auto grid = RadiusGrid::build(compact.points, to_cloud, radius, stop, stopped);
    // Stopped: not remembered (the grid is incomplete); the tree answers until the caller,
    // which checks the same token, gives up.
    if (stopped) return nullptr;
    grids.emplace_back(radius, std::move(grid));
    return grids.back().second.get();
  }
};

NeighborSearch::NeighborSearch(const std::vector<Vec3f>& points, std::stop_token stop)
    : impl_(std::make_unique<Impl>()) {
  if (points.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("neighbour search: more than 2^32-1 points");
  impl_->stop = std::move(stop);
  const std::stop_token& token = impl_->stop;
  impl_->compact.points.reserve(points.size());
  impl_->to_cloud.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (i % kCheckEvery == 0) throw_if_stopped(token, "building the neighbour index");
    if (!is_finite(points[i])) continue;
    impl_->compact.points.push_back(points[i]);
    impl_->to_cloud.push_back(static_cast<std::uint32_t>(i));
  }
  throw_if_stopped(token, "building the neighbour index");
  impl_->tree = std::make_unique<KdTree>(
      3, impl_->compact,
      nanoflann::KDTreeSingleIndexAdaptorParams(
          16, nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex));
  build_checked(*impl_->tree, token);
}

NeighborSearch::~NeighborSearch() = default;

std::size_t NeighborSearch::indexed_points() const { return impl_->compact.points.size(); }

void NeighborSearch::find(const Vec3f& query, const Neighborhood& hood, NeighborList& out,
                          bool sorted) const {
  out.clear();
  if (!is_finite(query) || impl_->compact.points.empty()) return;
  if (!hood.valid()) throw std::invalid_argument("invalid neighbourhood: " + hood.describe());

  if (hood.k > 0) {
    nearest(query, std::min<std::size_t>(hood.k, impl_->compact.points.size()),
            std::numeric_limits<float>::max(), out);
    return;
  }
  const float sq_radius = hood.radius * hood.radius;
  if (hood.max_neighbors == 0) {
    if (const RadiusGrid* grid = impl_->grid_for(hood.radius)) {
      grid->find(query, sq_radius, hood.radius, out);
      if (sorted) sort_by_distance(out);
      return;
    }
    RadiusCollector collector(sq_radius, impl_->to_cloud, out);
    impl_->tree->findNeighbors(collector, query.data(), nanoflann::SearchParams(32, 0.0f, false));
    if (sorted) sort_by_distance(out);
    return;
  }

  // Hybrid: the nearest max_neighbors within the radius. An unsorted query first tries the
  // plain radius search, bounded so that it never reads more than a few times the cap; when the
  // radius holds no more than the cap its answer is the same set (and, unsorted, the same list
  // the uncapped radius search gives). Otherwise, or sorted, the nearest set answers.
  const std::size_t cap = static_cast<std::size_t>(hood.max_neighbors);
  if (!sorted) {
    if (const RadiusGrid* grid = impl_->grid_for(hood.radius)) {
      if (grid->candidates(query, hood.radius) <= kCandidatesPerNeighbor * cap) {
        grid->find(query, sq_radius, hood.radius, out);
        if (out.size() <= cap) return;
        out.clear();
      }
    } else {
      BoundedRadiusCollector collector(sq_radius, cap, impl_->to_cloud, out);
      impl_->tree->findNeighbors(collector, query.data(), nanoflann::SearchParams(32, 0.0f, false));
      if (!collector.overflowed()) return;
      out.clear();
    }
  }
  nearest(query, std::min(cap, impl_->compact.points.size()), sq_radius, out);
}

void NeighborSearch::nearest(const Vec3f& query, std::size_t capacity, float sq_bound,
                             NeighborList& out) const {
  NearestSet result(capacity, sq_bound);
  impl_->tree->findNeighbors(result, query.data(), nanoflann::SearchParams());
  result.write(impl_->to_cloud, out);
  // Points exactly at the bound are outside a radius ("strictly inside").
  std::size_t found = out.size();
  while (found > 0 && !(out.sq_dists[found - 1] < sq_bound)) --found;
  out.indices.resize(found);
  out.sq_dists.resize(found);
}

}  // namespace primlabel
