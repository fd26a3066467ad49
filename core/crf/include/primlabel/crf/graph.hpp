#pragma once
// The CRF's neighbourhood graph: undirected, stored as CSR adjacency over every point of a cloud.
// Points without a valid descriptor are nodes too (so node index == point index) but have no
// edges and are marked inactive; inference gives them the unknown label.
//
// Each undirected edge {i, j} appears twice, as the directed slots i->j (in row i) and j->i (in
// row j); reverse[p] is the slot of the opposite direction, so message passing can write the
// message i->j straight into the receiver's row. Rows are sorted by neighbour index, so the graph
// depends only on the points and descriptors, never on the thread count.

#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "primlabel/geometry/descriptors.hpp"
#include "primlabel/geometry/neighbor_lists.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::crf {

struct Graph {
  std::vector<std::uint32_t> offsets;    // num_nodes() + 1 row starts into `neighbors`
  std::vector<std::uint32_t> neighbors;  // directed slots: neighbors[p] is the head of slot p
  std::vector<std::uint32_t> reverse;    // reverse[p]: slot of the opposite direction of p
  std::vector<std::uint8_t> active;      // 1 = the node has a descriptor and takes part

  std::size_t num_nodes() const { return active.size(); }
  std::size_t num_slots() const { return neighbors.size(); }      // directed edges
  std::size_t num_edges() const { return neighbors.size() / 2; }  // undirected edges
  std::size_t num_active() const;
  std::uint32_t degree(std::size_t node) const { return offsets[node + 1] - offsets[node]; }
  std::span<const std::uint32_t> neighbors_of(std::size_t node) const {
    return {neighbors.data() + offsets[node], degree(node)};
  }
};

// What defines a model's graph, stored in model files (how a call runs is a RunContext).
struct GraphSettings {
  // Neighbours of each point, not counting the point itself: Knn(8) links every point to its 8
  // nearest others; Radius(r) / Hybrid(r, m) to the others within r (the m nearest of them).
  Neighborhood neighborhood = Neighborhood::Knn(8);
};

// A row of `dim` values is a valid descriptor when every value is finite (features.hpp marks
// invalid points with NaN rows; all-zero rows of isolated points are valid).
bool descriptor_is_valid(std::span<const float> row);
std::vector<std::uint8_t> valid_descriptor_mask(const Descriptors& descriptors);

// Links every point with a valid descriptor to its neighbours among the points with a valid
// descriptor, then symmetrises (union: i~j when either finds the other). `descriptors` has one
// row per point. `search` may be passed to reuse an index built on `points` (otherwise one is
// built); points without a valid descriptor are filtered out of its answers, so the graph never
// depends on whether it was passed. Throws primlabel::Cancelled when context.stop is requested
// (checked per block of points, and while the graph's own neighbour index is built). The graph
// is identical for any context.threads. `shared` (shared radius lists on `points`, with `search`)
// answer a k-nearest graph where they hold the k nearest: the k nearest with ties broken by
// index, which may differ from the tree's tie order only between exactly equidistant points.
Graph build_graph(const std::vector<Vec3f>& points, const Descriptors& descriptors,
                  const GraphSettings& settings = {}, const RunContext& context = {},
                  const NeighborSearch* search = nullptr, const NeighborLists* shared = nullptr);

// A graph from an explicit undirected edge list (tests, synthetic data, other sources). Self
// loops, duplicates and edges touching inactive nodes are dropped. `active` defaults to all.
Graph graph_from_edges(std::size_t num_nodes,
                       std::span<const std::pair<std::uint32_t, std::uint32_t>> edges,
                       std::vector<std::uint8_t> active = {});

// Same graph, but nodes with active_mask[i] == 0 are deactivated and lose their edges (e.g. to
// leave unlabelled points out of a likelihood).
Graph restrict_graph(const Graph& graph, std::span<const std::uint8_t> active_mask);

}  // namespace primlabel::crf
