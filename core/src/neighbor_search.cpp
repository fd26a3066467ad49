#include "primlabel/core/neighbor_search.hpp"

// Equal distances are reported lowest index first, so k-nearest lists are reproducible.
#define NANOFLANN_FIRST_MATCH
#include <nanoflann.hpp>

#include <algorithm>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

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

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, CompactPoints>,
                                                   CompactPoints, 3, std::uint32_t>;

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
  CompactPoints compact;
  std::vector<std::uint32_t> to_cloud;  // compact index -> cloud index
  std::unique_ptr<KdTree> tree;
};

NeighborSearch::NeighborSearch(const std::vector<Vec3f>& points) : impl_(std::make_unique<Impl>()) {
  if (points.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("neighbour search: more than 2^32-1 points");
  impl_->compact.points.reserve(points.size());
  impl_->to_cloud.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!is_finite(points[i])) continue;
    impl_->compact.points.push_back(points[i]);
    impl_->to_cloud.push_back(static_cast<std::uint32_t>(i));
  }
  impl_->tree = std::make_unique<KdTree>(3, impl_->compact,
                                         nanoflann::KDTreeSingleIndexAdaptorParams(16));
}

NeighborSearch::~NeighborSearch() = default;

std::size_t NeighborSearch::indexed_points() const { return impl_->compact.points.size(); }

void NeighborSearch::find(const Vec3f& query, const Neighborhood& hood, NeighborList& out,
                          bool sorted) const {
  out.clear();
  if (!is_finite(query) || impl_->compact.points.empty()) return;
  if (!hood.valid()) throw std::invalid_argument("invalid neighbourhood: " + hood.describe());

  const bool knn_like = hood.k > 0 || hood.max_neighbors > 0;
  if (!knn_like) {
    RadiusCollector collector(hood.radius * hood.radius, impl_->to_cloud, out);
    impl_->tree->findNeighbors(collector, query.data(), nanoflann::SearchParams(32, 0.0f, false));
    if (sorted) sort_by_distance(out);
    return;
  }

  // k-nearest, or hybrid: the nearest max_neighbors, pruned at the radius from the start.
  const std::size_t capacity =
      std::min<std::size_t>(hood.k > 0 ? hood.k : hood.max_neighbors, impl_->compact.points.size());
  out.indices.resize(capacity);
  out.sq_dists.resize(capacity);
  nanoflann::KNNResultSet<float, std::uint32_t> result(capacity);
  result.init(out.indices.data(), out.sq_dists.data());
  const float sq_radius = hood.radius * hood.radius;
  if (hood.radius > 0.0f) out.sq_dists[capacity - 1] = sq_radius;
  impl_->tree->findNeighbors(result, query.data(), nanoflann::SearchParams());
  std::size_t found = result.size();
  if (hood.radius > 0.0f)
    while (found > 0 && !(out.sq_dists[found - 1] < sq_radius)) --found;
  out.indices.resize(found);
  out.sq_dists.resize(found);
  for (auto& index : out.indices) index = impl_->to_cloud[index];
}

}  // namespace primlabel
