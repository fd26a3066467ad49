// Connected components by union-find over capped radius neighbourhoods. Neighbour lists are
// searched in parallel, a slice of points at a time (bounded memory), and merged in point order;
// the components of a graph do not depend on the order its edges are merged in anyway.

#include "primlabel/primitives/segmentation.hpp"

#include <algorithm>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/parallel.hpp"
#include "primlabel/geometry/point_spacing.hpp"

namespace primlabel::primitives {
namespace {

constexpr std::size_t kSlicePoints = 1 << 16;
constexpr std::size_t kBlockPoints = 1024;

class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), std::uint32_t{0});
  }
  std::uint32_t find(std::uint32_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<std::uint32_t> parent_;
};

float linking_radius(const std::vector<Vec3f>& xyz, const NeighborSearch& search,
                     const SegmentOptions& options, float known_spacing) {
  if (options.radius > 0.0f) return options.radius;
  const float spacing =
      std::isnan(known_spacing) ? median_point_spacing(xyz, search) : known_spacing;
  return std::isfinite(spacing) ? std::max(4.0f * spacing, 1e-3f) : 1e-3f;
}

}  // namespace

void SegmentOptions::validate() const {
  if (!(radius >= 0.0f) || !std::isfinite(radius))
    throw std::invalid_argument("segment radius must be finite and >= 0");
  if (max_neighbors < 1 || max_neighbors > 1024)
    throw std::invalid_argument("segment max neighbours must be in [1, 1024]");
  if (min_points < 1) throw std::invalid_argument("segment min points must be at least 1");
  if (max_segments < 1) throw std::invalid_argument("max segments must be at least 1");
}

Segmentation segment_by_label(const std::vector<Vec3f>& xyz, std::span<const std::uint32_t> labels,
                              const SegmentOptions& options, const RunContext& context,
                              const SharedNeighbors& shared) {
  options.validate();
  if (labels.size() != xyz.size())
    throw std::invalid_argument("segmentation: " + std::to_string(labels.size()) + " labels for " +
                                std::to_string(xyz.size()) + " points");
  if (xyz.size() >= kNoSegment)
    throw std::invalid_argument("segmentation: too many points for 32-bit segment ids");
  Segmentation out;
  const std::size_t n = xyz.size();
  out.point_segment.assign(n, kNoSegment);
  if (n == 0) return out;
  std::optional<NeighborSearch> own_search;
  if (!shared.search) own_search.emplace(xyz, context.stop);
  const NeighborSearch& search = shared.search ? *shared.search : *own_search;
  out.radius =
      linking_radius(xyz, search, options, shared.search ? shared.point_spacing : float(NAN));
  const Neighborhood hood = Neighborhood::Hybrid(out.radius, options.max_neighbors);
  // The lists hold the same neighbour set as a search (NeighborLists::find) when the linking
  // radius is within theirs; the order differs, which components do not depend on.
  const NeighborLists* lists =
      shared.search && shared.lists && out.radius <= shared.lists->neighborhood().radius
          ? shared.lists
          : nullptr;
  auto eligible = [&](std::size_t i) {
    return is_finite(xyz[i]) && !(options.skip_unknown && labels[i] == 0);
  };

  DisjointSets sets(n);
  for (std::size_t slice = 0; slice < n; slice += kSlicePoints) {
    const std::size_t end = std::min(n, slice + kSlicePoints);
    const std::size_t blocks = (end - slice + kBlockPoints - 1) / kBlockPoints;
    std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> edges(blocks);
    primlabel::detail::for_each_block(
        std::ptrdiff_t(blocks), context, [] { return NeighborList{}; },
        [&](NeighborList& list, std::ptrdiff_t block) {
          const std::size_t first = slice + std::size_t(block) * kBlockPoints;
          const std::size_t last = std::min(end, first + kBlockPoints);
          for (std::size_t i = first; i < last; ++i) {
            if (!eligible(i)) continue;
            if (lists)
              lists->find(i, hood, list);
            else
              search.find(xyz[i], hood, list, false);
            for (std::uint32_t j : list.indices)
              if (j > i && labels[j] == labels[i]) edges[block].emplace_back(std::uint32_t(i), j);
          }
        });
    context.throw_if_stopped("segmentation");
    for (const auto& block_edges : edges)
      for (const auto& [a, b] : block_edges) sets.unite(a, b);
  }

  // Members per root in ascending point order: the root is the lowest index (unite keeps it).
  std::vector<std::uint32_t> component(n, kNoSegment);
  std::vector<std::vector<std::uint32_t>> members;
  for (std::size_t i = 0; i < n; ++i) {
    if (!eligible(i)) continue;
    const std::uint32_t root = sets.find(std::uint32_t(i));
    if (component[root] == kNoSegment) {
      component[root] = std::uint32_t(members.size());
      members.emplace_back();
    }
    members[component[root]].push_back(std::uint32_t(i));
  }
  std::vector<std::size_t> order;
  for (std::size_t c = 0; c < members.size(); ++c)
    if (members[c].size() >= options.min_points) order.push_back(c);
  // Components were created in order of their lowest index, so a stable sort by size breaks
  // ties by it.
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return members[a].size() > members[b].size();
  });
  if (order.size() > options.max_segments) order.resize(options.max_segments);
  for (std::size_t c : order) {
    const auto id = std::uint32_t(out.segments.size());
    for (std::uint32_t i : members[c]) out.point_segment[i] = id;
    out.labels.push_back(labels[members[c].front()]);
    out.segments.push_back(std::move(members[c]));
  }
  return out;
}

}  // namespace primlabel::primitives
