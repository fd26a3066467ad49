#include "primlabel/geometry/neighbor_search.hpp"

// Equal distances are reported lowest index first, so k-nearest lists are reproducible.
#define NANOFLANN_FIRST_MATCH
#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <nanoflann.hpp>
#include <numeric>
#include <span>
#include <sstream>
#include <stdexcept>
#include <variant>

#include "finite_points.hpp"
#include "primlabel/geometry/cancellation.hpp"
#include "radius_grid.hpp"

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

using detail::FinitePoints;
using detail::RadiusGrid;

constexpr const char* kWhat = "building the neighbour index";
// While nanoflann builds the tree, reads of points whose index is a multiple of 4096 check the
// stop token: every node split reads all of the node's points (in index-random order), so about
// one read in 4096 checks, some every few microseconds, without a counter to update per read.
constexpr std::size_t kCheckMask = (std::size_t(1) << 12) - 1;
// A capped radius query on a grid reads its cells only when they hold at most this many points
// per allowed neighbour (a sphere fills ~1/6 of the cells' box in 3D, ~1/3 on a surface).
constexpr std::size_t kCandidatesPerNeighbor = 8;

// Clouds this large check the stop token while nanoflann builds their tree (a 5M-point build
// takes seconds); smaller ones build in tens of milliseconds and are checked only before and
// after, since the check on every read slows every build down.
constexpr std::size_t kCheckedBuildPoints = std::size_t(1) << 19;

// nanoflann dataset adaptor over the finite points. Only the build reads points through it (the
// distance below reads them directly), so the build is the only code that pays for its stop
// check: nanoflann's buildIndex() has no cancellation of its own, but every node it splits reads
// its points here, and an exception thrown here unwinds it (the tree is then discarded).
static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be three packed floats");
template <bool kCheckStop>
struct TreePoints {
  explicit TreePoints(const FinitePoints& finite, const std::stop_token& stop)
      : points(finite),
        xyz(reinterpret_cast<const float*>(finite.cloud())),
        map(finite.map()),
        build_stop(stop) {}
  const FinitePoints& points;
  // The same points as raw arrays: a 5M-point build reads coordinates ~10^8 times.
  const float* xyz;          // cloud index * 3 + dim
  const std::uint32_t* map;  // tree index -> cloud index, or nullptr: the identity
  const std::stop_token& build_stop;

  std::size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const {
    if constexpr (kCheckStop) {
      if ((i & kCheckMask) == 0) [[unlikely]]
        check_stop();
    }
    return xyz[3 * std::size_t(map ? map[i] : i) + dim];
  }
  // Out of line, so that the read above stays small enough to inline into nanoflann's loops.
  [[gnu::noinline, gnu::cold]] void check_stop() const { throw_if_stopped(build_stop, kWhat); }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

// nanoflann's L2_Simple_Adaptor (the same arithmetic: ((0 + dx^2) + dy^2) + dz^2), reading the
// points without the adaptor's build-time stop check.
template <class Points>
struct TreeDistance {
  using ElementType = float;
  using DistanceType = float;
  const float* xyz;
  const std::uint32_t* map;
  explicit TreeDistance(const Points& d) : xyz(d.xyz), map(d.map) {}
  float evalMetric(const float* a, std::uint32_t b, std::size_t size) const {
    const float* p = xyz + 3 * std::size_t(map ? map[b] : b);
    float result = 0.0f;
    for (std::size_t i = 0; i < size; ++i) {
      const float diff = a[i] - p[i];
      result += diff * diff;
    }
    return result;
  }
  template <typename U, typename V>
  float accum_dist(const U a, const V b, std::size_t) const {
    return (a - b) * (a - b);
  }
};

// The two trees differ only in their build; queries go to whichever was built.
template <bool kCheckStop>
struct Tree {
  using Points = TreePoints<kCheckStop>;
  using Index = nanoflann::KDTreeSingleIndexAdaptor<TreeDistance<Points>, Points, 3, std::uint32_t>;
  Points points;
  Index index;
  Tree(const FinitePoints& finite, const std::stop_token& stop)
      : points(finite, stop),
        index(3, points,
              nanoflann::KDTreeSingleIndexAdaptorParams(
                  16, nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex)) {
    index.buildIndex();
  }
};
using AnyTree = std::variant<std::unique_ptr<Tree<false>>, std::unique_ptr<Tree<true>>>;

// Result-set filters, by cloud index.
struct AcceptAll {
  bool operator()(std::uint32_t) const { return true; }
};
struct AcceptMask {
  std::span<const std::uint8_t> allowed;
  bool operator()(std::uint32_t cloud_index) const { return allowed[cloud_index] != 0; }
};

// Collects every accepted point strictly inside the radius straight into the caller's
// NeighborList, translating tree indices to cloud indices.
template <class Accept>
class RadiusCollector {
 public:
  RadiusCollector(float sq_radius, const FinitePoints& points, const Accept& accept,
                  NeighborList& out)
      : sq_radius_(sq_radius), points_(points), accept_(accept), out_(out) {}
  std::size_t size() const { return out_.indices.size(); }
  bool full() const { return true; }
  float worstDist() const { return sq_radius_; }
  bool addPoint(float sq_dist, std::uint32_t tree_index) {
    const std::uint32_t index = points_.cloud_index(tree_index);
    if (sq_dist < sq_radius_ && accept_(index)) {
      out_.indices.push_back(index);
      out_.sq_dists.push_back(sq_dist);
    }
    return true;
  }

 private:
  float sq_radius_;
  const FinitePoints& points_;
  const Accept& accept_;
  NeighborList& out_;
};

// Collects points like RadiusCollector, but gives up (and ends the search) once more than
// `limit` are found: a capped radius query then asks for the nearest instead, so a dense
// cluster costs O(limit), not O(cluster).
template <class Accept>
class BoundedRadiusCollector {
 public:
  BoundedRadiusCollector(float sq_radius, std::size_t limit, const FinitePoints& points,
                         const Accept& accept, NeighborList& out)
      : sq_radius_(sq_radius), limit_(limit), points_(points), accept_(accept), out_(out) {}
  std::size_t size() const { return out_.indices.size(); }
  bool full() const { return true; }
  float worstDist() const { return sq_radius_; }
  bool addPoint(float sq_dist, std::uint32_t tree_index) {
    const std::uint32_t index = points_.cloud_index(tree_index);
    if (!(sq_dist < sq_radius_) || !accept_(index)) return true;
    if (out_.indices.size() == limit_) {
      overflowed_ = true;
      return false;  // nanoflann stops the whole search
    }
    out_.indices.push_back(index);
    out_.sq_dists.push_back(sq_dist);
    return true;
  }
  bool overflowed() const { return overflowed_; }

 private:
  float sq_radius_;
  std::size_t limit_;
  const FinitePoints& points_;
  const Accept& accept_;
  NeighborList& out_;
  bool overflowed_ = false;
};

// The `capacity` nearest accepted points closer than `bound`, exactly the set nanoflann's
// KNNResultSet keeps (with NANOFLANN_FIRST_MATCH: ordered by distance, then index), but in a
// max-heap: an insertion costs O(log k), not O(k), so large caps stay cheap. Once full at
// distance 0 nothing can enter any more; worstDist() < 0 then prunes every remaining subtree,
// where nanoflann would visit every coincident point (N^2 for N duplicates). Tree indices
// increase with cloud indices, so ordering by either is the same.
template <class Accept>
class NearestSet {
 public:
  NearestSet(std::size_t capacity, float bound, const FinitePoints& points, const Accept& accept)
      : capacity_(capacity), bound_(bound), points_(points), accept_(accept) {
    heap_.reserve(capacity);
  }
  std::size_t size() const { return heap_.size(); }
  bool full() const { return heap_.size() == capacity_; }
  float worstDist() const {
    if (!full()) return bound_;
    const float worst = heap_.front().first;
    return worst > 0.0f ? worst : -1.0f;
  }
  bool addPoint(float sq_dist, std::uint32_t tree_index) {
    if (!accept_(points_.cloud_index(tree_index))) return true;
    const Entry entry{sq_dist, tree_index};
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
  // Sorted by (distance, index), translated to cloud indices.
  void write(NeighborList& out) {
    std::sort_heap(heap_.begin(), heap_.end());
    out.indices.resize(heap_.size());
    out.sq_dists.resize(heap_.size());
    for (std::size_t j = 0; j < heap_.size(); ++j) {
      out.sq_dists[j] = heap_[j].first;
      out.indices[j] = points_.cloud_index(heap_[j].second);
    }
  }

 private:
  using Entry = std::pair<float, std::uint32_t>;
  std::size_t capacity_;
  float bound_;
  const FinitePoints& points_;
  const Accept& accept_;
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

struct NeighborSearch::Impl {
  Impl(const std::vector<Vec3f>& cloud, std::stop_token token)
      : stop(std::move(token)), points(cloud, stop) {}

  std::stop_token stop;  // cuts the tree build and lazy grid builds short
  FinitePoints points;
  AnyTree tree;

  template <class ResultSet>
  void search_tree(ResultSet& result, const Vec3f& query,
                   const nanoflann::SearchParams& params) const {
    std::visit([&](const auto& t) { t->index.findNeighbors(result, query.data(), params); }, tree);
  }

  // Radius grids are built on first use for a radius and kept; a radius that does not suit a
  // grid is remembered as such (nullptr) so the tree answers it.
  std::mutex grids_mutex;
  std::vector<std::pair<float, std::unique_ptr<RadiusGrid>>> grids;

  const RadiusGrid* grid_for(float radius) {
    std::lock_guard<std::mutex> lock(grids_mutex);
    for (const auto& [r, grid] : grids)
      if (r == radius) return grid.get();
    bool stopped = false;
    auto grid = RadiusGrid::build(points, radius, stop, stopped);
    // Stopped: not remembered (the grid is incomplete); the tree answers until the caller,
    // which checks the same token, gives up.
    if (stopped) return nullptr;
    grids.emplace_back(radius, std::move(grid));
    return grids.back().second.get();
  }

  // The `capacity` nearest accepted points strictly closer than sq_bound, sorted.
  template <class Accept>
  void nearest(const Vec3f& query, std::size_t capacity, float sq_bound, const Accept& accept,
               NeighborList& out) const {
    NearestSet<Accept> result(capacity, sq_bound, points, accept);
    search_tree(result, query, nanoflann::SearchParams());
    result.write(out);
    // Points exactly at the bound are outside a radius ("strictly inside").
    std::size_t found = out.size();
    while (found > 0 && !(out.sq_dists[found - 1] < sq_bound)) --found;
    out.indices.resize(found);
    out.sq_dists.resize(found);
  }

  template <class Accept>
  void find(const Vec3f& query, const Neighborhood& hood, const Accept& accept, NeighborList& out,
            bool sorted) {
    out.clear();
    if (!is_finite(query) || points.size() == 0) return;
    if (!hood.valid()) throw std::invalid_argument("invalid neighbourhood: " + hood.describe());

    if (hood.k > 0) {
      nearest(query, std::min<std::size_t>(hood.k, points.size()),
              std::numeric_limits<float>::max(), accept, out);
      return;
    }
    const float sq_radius = hood.radius * hood.radius;
    if (hood.max_neighbors == 0) {
      if (const RadiusGrid* grid = grid_for(hood.radius)) {
        grid->find(query, sq_radius, hood.radius, accept, out);
        if (sorted) sort_by_distance(out);
        return;
      }
      RadiusCollector<Accept> collector(sq_radius, points, accept, out);
      search_tree(collector, query, nanoflann::SearchParams(32, 0.0f, false));
      if (sorted) sort_by_distance(out);
      return;
    }

    // Hybrid: the nearest max_neighbors within the radius. An unsorted query first tries the
    // plain radius search, bounded so that it never reads more than a few times the cap; when
    // the radius holds no more than the cap its answer is the same set (and, unsorted, the same
    // list the uncapped radius search gives). Otherwise, or sorted, the nearest set answers.
    const std::size_t cap = static_cast<std::size_t>(hood.max_neighbors);
    if (!sorted) {
      if (const RadiusGrid* grid = grid_for(hood.radius)) {
        if (grid->find(query, sq_radius, hood.radius, accept, out, kCandidatesPerNeighbor * cap)) {
          if (out.size() <= cap) return;
          out.clear();
        }
      } else {
        BoundedRadiusCollector<Accept> collector(sq_radius, cap, points, accept, out);
        search_tree(collector, query, nanoflann::SearchParams(32, 0.0f, false));
        if (!collector.overflowed()) return;
        out.clear();
      }
    }
    nearest(query, std::min(cap, points.size()), sq_radius, accept, out);
  }
};

NeighborSearch::NeighborSearch(const std::vector<Vec3f>& points, std::stop_token stop)
    : impl_(std::make_unique<Impl>(points, std::move(stop))) {
  Impl& impl = *impl_;
  throw_if_stopped(impl.stop, kWhat);
  // nanoflann's own build through its public API; for a large cloud the adaptor checks the
  // token while it runs.
  if (impl.points.size() >= kCheckedBuildPoints)
    impl.tree = std::make_unique<Tree<true>>(impl.points, impl.stop);
  else
    impl.tree = std::make_unique<Tree<false>>(impl.points, impl.stop);
  throw_if_stopped(impl.stop, kWhat);
}

NeighborSearch::~NeighborSearch() = default;

std::size_t NeighborSearch::indexed_points() const { return impl_->points.size(); }

void NeighborSearch::find(const Vec3f& query, const Neighborhood& hood, NeighborList& out,
                          bool sorted) const {
  impl_->find(query, hood, AcceptAll{}, out, sorted);
}

void NeighborSearch::find(const Vec3f& query, const Neighborhood& hood,
                          std::span<const std::uint8_t> allowed, NeighborList& out,
                          bool sorted) const {
  if (allowed.size() != impl_->points.cloud_size())
    throw std::invalid_argument("neighbour search: allowed mask is not one entry per point");
  impl_->find(query, hood, AcceptMask{allowed}, out, sorted);
}

}  // namespace primlabel
