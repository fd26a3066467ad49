#include "primlabel/geometry/neighbor_lists.hpp"

#include <algorithm>
#include <atomic>
#include <limits>
#include <stdexcept>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel {

namespace {
// States of a point's list besides an offset.
constexpr std::uint32_t kNotKept = std::numeric_limits<std::uint32_t>::max();  // over budget
constexpr std::uint32_t kCut = kNotKept - 1;      // the shared search hit its cap here
constexpr std::uint32_t kNoPoint = kNotKept - 2;  // non-finite: no neighbours
constexpr std::size_t kEntryBytes = sizeof(std::uint32_t) + sizeof(float);

bool is_cut(const Neighborhood& hood, const NeighborList& found) {
  return hood.max_neighbors > 0 && found.size() >= std::size_t(hood.max_neighbors);
}
}  // namespace

NeighborLists::NeighborLists(const std::vector<Vec3f>& points, const NeighborSearch& search,
                             const Neighborhood& hood, std::size_t budget_bytes,
                             const RunContext& context)
    : NeighborLists(points, search, hood, budget_bytes, {}, context) {}

NeighborLists::NeighborLists(const std::vector<Vec3f>& points, const NeighborSearch& search,
                             const Neighborhood& hood, std::size_t budget_bytes,
                             std::span<const std::uint8_t> wanted, const RunContext& context)
    : points_(points), search_(search), hood_(hood) {
  if (!hood.valid() || !(hood.radius > 0.0f))
    throw std::invalid_argument("neighbour lists need a radius neighbourhood, got " +
                                hood.describe());
  const std::size_t n = points.size();
  if (!wanted.empty() && wanted.size() != n)
    throw std::invalid_argument("neighbour lists: " + std::to_string(wanted.size()) +
                                " wanted flags for " + std::to_string(n) + " points");
  blocks_.resize((n + kBlock - 1) / kBlock);
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const std::size_t size = std::min(n, (b + 1) * kBlock) - b * kBlock;
    blocks_[b].begin.assign(size, kNotKept);
    blocks_[b].end.assign(size, kNotKept);
  }
  const std::size_t block_budget = blocks_.empty() ? 0 : budget_bytes / blocks_.size();
  if (wanted.empty()) {
    fill([](std::size_t) { return true; }, block_budget, context);
    return;
  }
  fill([&](std::size_t i) { return wanted[i] != 0; }, block_budget, context);
  // The wanted points' neighbours, from the lists just kept (or searched again).
  std::vector<std::uint8_t> needed(wanted.begin(), wanted.end());
  NeighborList scratch;
  for (std::size_t i = 0; i < n; ++i) {
    if (!wanted[i]) continue;
    const std::uint32_t* indices = nullptr;
    const float* sq_dists = nullptr;
    std::size_t count = 0;
    if (!shared(i, scratch, indices, sq_dists, count)) {  // cut: its nearest are searched anew
      search.find(points[i], hood, scratch, /*sorted=*/false);
      indices = scratch.indices.data(), count = scratch.size();
    }
    for (std::size_t p = 0; p < count; ++p) needed[indices[p]] = 1;
  }
  fill([&](std::size_t i) { return needed[i] != 0; }, block_budget, context);
}

template <typename Take>
void NeighborLists::fill(const Take& take, std::size_t block_budget, const RunContext& context) {
  const std::stop_token& stop = context.stop;
  const std::size_t n = points_.size();
  std::atomic<std::size_t> kept{0};
  detail::for_each_block(
      static_cast<std::ptrdiff_t>(blocks_.size()), context, [] { return NeighborList(); },
      [&](NeighborList& found, std::ptrdiff_t b) {
        Block& block = blocks_[std::size_t(b)];
        const std::size_t first = std::size_t(b) * kBlock;
        const std::size_t last = std::min(n, first + kBlock);
        std::size_t block_kept = 0;
        for (std::size_t i = first; i < last; ++i) {
          if (stop.stop_requested()) return;  // per point: within one neighbourhood's time
          const std::size_t slot = i - first;
          if (block.begin[slot] != kNotKept || !take(i)) continue;
          if (!is_finite(points_[i])) {
            block.begin[slot] = kNoPoint;
            continue;
          }
          // Over this block's share: the rest of it is searched again when asked for.
          if ((block.indices.size() + 1) * kEntryBytes > block_budget) break;
          search_.find(points_[i], hood_, found, /*sorted=*/false);
          if (is_cut(hood_, found)) {
            block.begin[slot] = kCut;
            continue;
          }
          if ((block.indices.size() + found.size()) * kEntryBytes > block_budget) break;
          block.begin[slot] = static_cast<std::uint32_t>(block.indices.size());
          block.indices.insert(block.indices.end(), found.indices.begin(), found.indices.end());
          block.sq_dists.insert(block.sq_dists.end(), found.sq_dists.begin(), found.sq_dists.end());
          block.end[slot] = static_cast<std::uint32_t>(block.indices.size());
          ++block_kept;
        }
        kept += block_kept;
      });
  throw_if_stopped(stop, "neighbour lists");
  kept_points_ += kept.load();
}

bool NeighborLists::shared(std::size_t i, NeighborList& scratch, const std::uint32_t*& indices,
                           const float*& sq_dists, std::size_t& count) const {
  const Block& block = blocks_[i / kBlock];
  const std::size_t slot = i % kBlock;
  const std::uint32_t begin = block.begin[slot];
  if (begin == kCut) return false;
  if (begin == kNoPoint) {
    count = 0;
    return true;
  }
  if (begin == kNotKept) {  // the same search again: the same list in the same order
    search_.find(points_[i], hood_, scratch, /*sorted=*/false);
    if (is_cut(hood_, scratch)) return false;
    indices = scratch.indices.data();
    sq_dists = scratch.sq_dists.data();
    count = scratch.size();
    return true;
  }
  indices = block.indices.data() + begin;
  sq_dists = block.sq_dists.data() + begin;
  count = block.end[slot] - begin;
  return true;
}

void NeighborLists::find(std::size_t i, const Neighborhood& hood, NeighborList& out) const {
  if (!(hood.radius > 0.0f) || hood.radius > hood_.radius)
    throw std::invalid_argument("neighbour lists of radius " + std::to_string(hood_.radius) +
                                " cannot answer " + hood.describe());
  thread_local NeighborList scratch;
  const std::uint32_t* indices = nullptr;
  const float* sq_dists = nullptr;
  std::size_t count = 0;
  if (shared(i, scratch, indices, sq_dists, count)) {
    // The same float comparison as the search's (squared distance < radius^2). Written
    // branch-free into room for all, then cut to what was kept.
    const float sq_radius = hood.radius * hood.radius;
    out.indices.resize(count);
    out.sq_dists.resize(count);
    std::uint32_t* out_indices = out.indices.data();
    float* out_sq = out.sq_dists.data();
    std::size_t kept = 0;
    for (std::size_t p = 0; p < count; ++p) {
      out_indices[kept] = indices[p];
      out_sq[kept] = sq_dists[p];
      kept += sq_dists[p] < sq_radius;
    }
    out.indices.resize(kept);
    out.sq_dists.resize(kept);
    // Within the cap the whole radius is the answer; beyond it the nearest are wanted.
    if (hood.max_neighbors == 0 || kept < std::size_t(hood.max_neighbors)) return;
  }
  search_.find(points_[i], hood, out, /*sorted=*/false);
}

std::span<const std::uint32_t> NeighborLists::view(std::size_t i, const Neighborhood& hood,
                                                   NeighborList& scratch) const {
  // The same radius means find()'s filter keeps every entry (the same float comparison), and
  // within the cap the filtered list is the answer.
  if (hood.radius == hood_.radius) {
    const std::uint32_t* indices = nullptr;
    const float* sq_dists = nullptr;
    std::size_t count = 0;
    if (shared(i, scratch, indices, sq_dists, count) &&
        (hood.max_neighbors == 0 || count < std::size_t(hood.max_neighbors)))
      return {indices, count};
    find(i, hood, scratch);
    return scratch.indices;
  }
  if (!(hood.radius > 0.0f) || hood.radius > hood_.radius)
    throw std::invalid_argument("neighbour lists of radius " + std::to_string(hood_.radius) +
                                " cannot answer " + hood.describe());
  // A smaller radius: find()'s filter, writing the indices alone (no distances to copy). A list
  // searched again lands in `scratch` itself and is compacted in place (kept <= p).
  const std::uint32_t* indices = nullptr;
  const float* sq_dists = nullptr;
  std::size_t count = 0;
  if (shared(i, scratch, indices, sq_dists, count)) {
    const float sq_radius = hood.radius * hood.radius;
    if (indices != scratch.indices.data()) scratch.indices.resize(count);
    std::uint32_t* out = scratch.indices.data();
    std::size_t kept = 0;
    for (std::size_t p = 0; p < count; ++p) {
      out[kept] = indices[p];
      kept += sq_dists[p] < sq_radius;  // the search's comparison, as in find()
    }
    scratch.indices.resize(kept);
    if (hood.max_neighbors == 0 || kept < std::size_t(hood.max_neighbors)) return scratch.indices;
  }
  search_.find(points_[i], hood, scratch, /*sorted=*/false);
  return scratch.indices;
}

namespace {
using Entry = std::pair<float, std::uint32_t>;  // (squared distance, index): a total order

// The `want` smallest entries among those with sq <= bound and allowed[index], kept sorted by
// insertion into `best` (k is small and most entries fail the first comparison); how many.
std::size_t smallest_within(const std::uint32_t* indices, const float* sq_dists, std::size_t count,
                            float bound, const std::vector<std::uint8_t>& allowed, Entry* best,
                            std::size_t want) {
  std::size_t have = 0;
  for (std::size_t p = 0; p < count; ++p) {
    const float sq = sq_dists[p];
    if (!(sq <= bound)) continue;
    if (have == want && sq > best[want - 1].first) continue;
    const Entry entry(sq, indices[p]);
    if (have == want && !(entry < best[want - 1])) continue;
    if (!allowed[entry.second]) continue;
    std::size_t j = have < want ? have++ : want - 1;
    for (; j > 0 && entry < best[j - 1]; --j) best[j] = best[j - 1];
    best[j] = entry;
  }
  return have;
}
}  // namespace

bool NeighborLists::nearest(std::size_t i, int k, const std::vector<std::uint8_t>& allowed,
                            NeighborList& out) const {
  if (k <= 0) return false;
  thread_local NeighborList scratch;
  const std::uint32_t* indices = nullptr;
  const float* sq_dists = nullptr;
  std::size_t count = 0;
  if (!shared(i, scratch, indices, sq_dists, count)) return false;
  constexpr std::size_t kOnStack = 32;
  Entry on_stack[kOnStack];
  std::vector<Entry> on_heap;
  const std::size_t want = std::size_t(k);
  if (want > kOnStack) on_heap.resize(want);
  Entry* best = want > kOnStack ? on_heap.data() : on_stack;
  // The lists are a few hundred long and the k nearest a few dozen: first only the entries
  // within twice the k-th squared distance of this thread's previous point (neighbouring points
  // have similar densities). Every entry left out is farther than all that were taken, so when
  // k of them are allowed they are the answer; otherwise the whole list decides. The bound
  // changes only the work, never the result, so the thread count cannot change it either.
  thread_local float previous_kth = 0.0f;
  std::size_t have = 0;
  if (previous_kth > 0.0f)
    have = smallest_within(indices, sq_dists, count, 2.0f * previous_kth, allowed, best, want);
  if (have < want)
    have = smallest_within(indices, sq_dists, count, std::numeric_limits<float>::infinity(),
                           allowed, best, want);
  if (have < want) return false;
  previous_kth = best[want - 1].first;
  out.indices.resize(want);
  out.sq_dists.resize(want);
  for (std::size_t j = 0; j < want; ++j) {
    out.sq_dists[j] = best[j].first;
    out.indices[j] = best[j].second;
  }
  return true;
}

}  // namespace primlabel
