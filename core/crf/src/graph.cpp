#include "primlabel/crf/graph.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel::crf {

using primlabel::detail::parallel_for;
using primlabel::detail::Schedule;

namespace {

constexpr const char* kWhat = "building the graph";
// Rows per stop check in the serial passes (well under a millisecond each); the parallel
// passes check once per OpenMP chunk.
constexpr std::size_t kCheckEvery = std::size_t(1) << 16;

void check_every(std::size_t i, const std::stop_token& stop) {
  if (i % kCheckEvery == 0) throw_if_stopped(stop, kWhat);
}

// One-directional adjacency lists of nodes [0, n) stored per block of kListBlock consecutive
// nodes in one flat buffer: a vector per node would cost a 120 MB allocation (and 5M frees)
// for a 5M-point cloud, neither of which can be interrupted.
class BlockLists {
 public:
  static constexpr std::size_t kListBlock = 256;

  explicit BlockLists(std::size_t n) : n_(n), blocks_((n + kListBlock - 1) / kListBlock) {}
  std::size_t size() const { return n_; }
  std::size_t num_blocks() const { return blocks_.size(); }
  // Node i's list; block b's lists are appended with start_node / push_back in node order.
  std::span<const std::uint32_t> operator[](std::size_t i) const {
    const Block& block = blocks_[i / kListBlock];
    const std::size_t r = i % kListBlock;
    if (r + 1 >= block.starts.size()) return {};  // the block was never filled (stopped)
    return {block.items.data() + block.starts[r], block.starts[r + 1] - block.starts[r]};
  }
  // Opens block b for filling; every node of it must then be started in order.
  void begin_block(std::size_t b) {
    Block& block = blocks_[b];
    block.starts.assign(1, 0);
    block.starts.reserve(kListBlock + 1);
  }
  void push_back(std::size_t b, std::uint32_t j) { blocks_[b].items.push_back(j); }
  std::size_t list_size(std::size_t b) const {
    const Block& block = blocks_[b];
    return block.items.size() - block.starts.back();
  }
  void end_node(std::size_t b) {
    blocks_[b].starts.push_back(static_cast<std::uint32_t>(blocks_[b].items.size()));
  }

 private:
  struct Block {
    std::vector<std::uint32_t> items;
    std::vector<std::uint32_t> starts;  // per node of the block, into items; one extra at the end
  };
  std::size_t n_;
  std::vector<Block> blocks_;
};

// BlockLists from per-node lists (the small serial callers).
BlockLists to_block_lists(const std::vector<std::vector<std::uint32_t>>& lists) {
  BlockLists out(lists.size());
  for (std::size_t b = 0; b < out.num_blocks(); ++b) {
    out.begin_block(b);
    const std::size_t last = std::min(lists.size(), (b + 1) * BlockLists::kListBlock);
    for (std::size_t i = b * BlockLists::kListBlock; i < last; ++i) {
      for (std::uint32_t j : lists[i]) out.push_back(b, j);
      out.end_node(b);
    }
  }
  return out;
}

// Symmetric CSR from one-directional adjacency lists: i~j when j is in lists[i] or i in lists[j].
// Throws Cancelled when `stop` is requested.
Graph assemble_symmetric(const BlockLists& lists, std::vector<std::uint8_t> active, int threads,
                         const std::stop_token& stop = {}) {
  const std::size_t n = active.size();
  Graph g;
  g.active = std::move(active);

  // Upper bound of each row (out + in), filled serially so the row contents are deterministic,
  // then sorted and deduplicated per row.
  std::vector<std::uint32_t> bound(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    check_every(i, stop);
    for (std::uint32_t j : lists[i]) {
      ++bound[i + 1];
      ++bound[j + 1];
    }
  }
  for (std::size_t i = 0; i < n; ++i) bound[i + 1] += bound[i];
  std::vector<std::uint32_t> raw(bound[n]);
  std::vector<std::uint32_t> fill(bound.begin(), bound.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    check_every(i, stop);
    for (std::uint32_t j : lists[i]) {
      raw[fill[i]++] = j;
      raw[fill[j]++] = static_cast<std::uint32_t>(i);
    }
  }
  std::vector<std::uint32_t> unique_count(n, 0);
  const long long nn = static_cast<long long>(n);
  // The parallel passes skip the rest of their chunk (1024 rows, starting at a multiple of
  // 1024) once stopped, and throw after the region.
  const auto skip = [&stop](long long i) { return i % 1024 == 0 && stop.stop_requested(); };
  const auto not_stopped = [] { return false; };  // each thread's "stopped" flag
  parallel_for(nn, threads, Schedule::Dynamic(1024), not_stopped,
               [&](bool& stopped, std::ptrdiff_t i) {
                 if (stopped || (stopped = skip(i))) return;
                 auto first = raw.begin() + bound[i];
                 auto last = raw.begin() + bound[i + 1];
                 std::sort(first, last);
                 unique_count[i] = static_cast<std::uint32_t>(std::unique(first, last) - first);
               });
  throw_if_stopped(stop, kWhat);

  g.offsets.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) g.offsets[i + 1] = g.offsets[i] + unique_count[i];
  g.neighbors.resize(g.offsets[n]);
  g.reverse.resize(g.offsets[n]);
  throw_if_stopped(stop, kWhat);
  parallel_for(nn, threads, Schedule::Dynamic(1024), [&](std::ptrdiff_t i) {
    std::copy_n(raw.begin() + bound[i], unique_count[i], g.neighbors.begin() + g.offsets[i]);
  });
  throw_if_stopped(stop, kWhat);
  parallel_for(nn, threads, Schedule::Dynamic(1024), not_stopped,
               [&](bool& stopped, std::ptrdiff_t i) {
                 if (stopped || (stopped = skip(i))) return;
                 for (std::uint32_t p = g.offsets[i]; p < g.offsets[i + 1]; ++p) {
                   const std::uint32_t j = g.neighbors[p];
                   const auto row_begin = g.neighbors.begin() + g.offsets[j];
                   const auto row_end = g.neighbors.begin() + g.offsets[j + 1];
                   g.reverse[p] = static_cast<std::uint32_t>(
                       std::lower_bound(row_begin, row_end, static_cast<std::uint32_t>(i)) -
                       g.neighbors.begin());
                 }
               });
  throw_if_stopped(stop, kWhat);
  return g;
}

// The query that returns the point itself plus the requested number of others.
Neighborhood query_with_self(const Neighborhood& hood) {
  Neighborhood q = hood;
  if (q.radius == 0.0f) q.k += 1;
  if (q.radius > 0.0f && q.max_neighbors > 0) q.max_neighbors += 1;
  return q;
}

int neighbor_cap(const Neighborhood& hood) {
  if (hood.radius == 0.0f) return hood.k;
  return hood.max_neighbors > 0 ? hood.max_neighbors : -1;
}

}  // namespace

std::size_t Graph::num_active() const {
  return static_cast<std::size_t>(std::count(active.begin(), active.end(), std::uint8_t{1}));
}

bool descriptor_is_valid(std::span<const float> row) {
  for (float v : row)
    if (!std::isfinite(v)) return false;
  return true;
}

std::vector<std::uint8_t> valid_descriptor_mask(const Descriptors& descriptors) {
  if (descriptors.dim <= 0)
    throw std::invalid_argument("valid_descriptor_mask: descriptor dimension <= 0");
  const std::size_t n = descriptors.size();
  std::vector<std::uint8_t> mask(n);
  for (std::size_t i = 0; i < n; ++i) mask[i] = descriptor_is_valid(descriptors.row(i)) ? 1 : 0;
  return mask;
}

Graph build_graph(const std::vector<Vec3f>& points, const Descriptors& descriptors,
                  const GraphSettings& settings, const RunContext& context,
                  const NeighborSearch* search, const NeighborLists* shared) {
  if (!settings.neighborhood.valid())
    throw std::invalid_argument("build_graph: invalid neighbourhood " +
                                settings.neighborhood.describe());
  if (descriptors.dim <= 0 ||
      descriptors.values.size() != points.size() * static_cast<std::size_t>(descriptors.dim))
    throw std::invalid_argument("build_graph: descriptors are not one row per point");
  const std::size_t n = points.size();
  const int threads = primlabel::detail::resolve_threads(context.threads);
  const std::stop_token& stop = context.stop;
  throw_if_stopped(stop, kWhat);

  std::vector<std::uint8_t> active(n);
  for (std::size_t i = 0; i < n; ++i) {
    check_every(i, stop);
    active[i] = descriptor_is_valid(descriptors.row(i)) ? 1 : 0;
  }
  bool every_finite_point_active = true;
  for (std::size_t i = 0; i < n; ++i) {
    check_every(i, stop);
    const bool finite = is_finite(points[i]);
    if (!finite) active[i] = 0;
    if (finite && !active[i]) every_finite_point_active = false;
  }

  // One index over the cloud's finite points (the caller's, or one built here). When some of
  // them lack a descriptor, the queries filter them out rather than a second index being built
  // over the active points: the same neighbours, without a copy of the cloud and a second tree.
  std::unique_ptr<NeighborSearch> own_search;
  if (!search) own_search = std::make_unique<NeighborSearch>(points, stop);
  const NeighborSearch& index = search ? *search : *own_search;
  const auto find = [&](const Vec3f& q, const Neighborhood& hood, NeighborList& found,
                        bool sorted) {
    if (every_finite_point_active)
      index.find(q, hood, found, sorted);
    else
      index.find(q, hood, active, found, sorted);
  };

  const Neighborhood query = query_with_self(settings.neighborhood);
  const int cap = neighbor_cap(settings.neighborhood);
  BlockLists lists(n);
  const auto blocks = static_cast<std::ptrdiff_t>(lists.num_blocks());
  primlabel::detail::for_each_block(
      blocks, context.with_threads(threads), [] { return NeighborList(); },
      [&](NeighborList& found, std::ptrdiff_t b) {
        lists.begin_block(b);
        const std::size_t last = std::min(n, std::size_t(b + 1) * BlockLists::kListBlock);
        for (std::size_t i = b * BlockLists::kListBlock; i < last; ++i) {
          if (stop.stop_requested()) return;  // per node: within one neighbourhood's time
          if (active[i]) {
            // Shared lists answer a k-nearest query (ties by index) when they hold the k.
            const bool listed =
                shared && query.radius == 0.0f && shared->nearest(i, query.k, active, found);
            if (!listed) find(points[i], query, found, /*sorted=*/cap >= 0);
            for (std::uint32_t j : found.indices) {
              if (j == static_cast<std::uint32_t>(i)) continue;
              if (cap >= 0 && static_cast<int>(lists.list_size(b)) >= cap) break;
              lists.push_back(b, j);
            }
          }
          lists.end_node(b);
        }
      });
  throw_if_stopped(stop, kWhat);
  return assemble_symmetric(lists, std::move(active), threads, stop);
}

Graph graph_from_edges(std::size_t num_nodes,
                       std::span<const std::pair<std::uint32_t, std::uint32_t>> edges,
                       std::vector<std::uint8_t> active) {
  if (active.empty()) active.assign(num_nodes, 1);
  if (active.size() != num_nodes)
    throw std::invalid_argument("graph_from_edges: active mask size != number of nodes");
  std::vector<std::vector<std::uint32_t>> lists(num_nodes);
  for (const auto& [a, b] : edges) {
    if (a >= num_nodes || b >= num_nodes)
      throw std::invalid_argument("graph_from_edges: edge endpoint out of range");
    if (a == b || !active[a] || !active[b]) continue;
    lists[a].push_back(b);
  }
  return assemble_symmetric(to_block_lists(lists), std::move(active), 1);
}

Graph restrict_graph(const Graph& graph, std::span<const std::uint8_t> active_mask) {
  const std::size_t n = graph.num_nodes();
  if (active_mask.size() != n)
    throw std::invalid_argument("restrict_graph: mask size != number of nodes");
  std::vector<std::uint8_t> active(n);
  for (std::size_t i = 0; i < n; ++i) active[i] = graph.active[i] && active_mask[i] ? 1 : 0;
  std::vector<std::vector<std::uint32_t>> lists(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!active[i]) continue;
    for (std::uint32_t j : graph.neighbors_of(i))
      if (j > i && active[j]) lists[i].push_back(j);
  }
  return assemble_symmetric(to_block_lists(lists), std::move(active), 1);
}

}  // namespace primlabel::crf
