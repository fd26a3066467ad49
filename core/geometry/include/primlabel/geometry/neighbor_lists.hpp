#pragma once
// One radius search per point shared by the stages that follow it: normals, FPFH and the CRF
// graph each need a neighbourhood of the same points (a radius, a smaller radius, the k nearest),
// and searching once at the largest radius and filtering is cheaper than three searches. The
// lists are kept within a byte budget; a point whose list is not kept (over the budget, or cut
// by the neighbourhood's cap) is searched again by the stage that needs it, with the same set.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel {

class NeighborLists {
 public:
  // Points per block of storage (each block is filled by one thread).
  static constexpr std::size_t kBlock = 256;

  // Searches `hood` (a radius or hybrid neighbourhood) around every finite point of `points`
  // with `search` (built on `points`) and keeps the lists while they fit in `budget_bytes` (8
  // bytes per neighbour; each block of points gets an equal share, so what is kept does not
  // depend on the thread count). `points` and `search` must outlive this object. Throws
  // std::invalid_argument for a k-nearest neighbourhood and Cancelled when context.stop is
  // requested (checked per point).
  NeighborLists(const std::vector<Vec3f>& points, const NeighborSearch& search,
                const Neighborhood& hood, std::size_t budget_bytes, const RunContext& context = {});

  // The same for a stage that needs only the points with wanted[i] != 0 and their neighbours
  // (an FPFH of a subset): only those lists are searched up front, wanted points first; the
  // others are searched when asked for, with the same answer. An empty `wanted` means all.
  NeighborLists(const std::vector<Vec3f>& points, const NeighborSearch& search,
                const Neighborhood& hood, std::size_t budget_bytes,
                std::span<const std::uint8_t> wanted, const RunContext& context = {});

  const Neighborhood& neighborhood() const { return hood_; }
  std::size_t kept_points() const { return kept_points_; }

  // The neighbours `search.find(points[i], hood)` returns (the same set and squared distances;
  // the order is that of the shared search, the same for a point whatever was kept). `hood` is a
  // radius or hybrid neighbourhood of radius <= neighborhood().radius. Points whose shared list
  // was not kept are searched again; thread-safe.
  void find(std::size_t i, const Neighborhood& hood, NeighborList& out) const;

  // The indices find(i, hood) gives, in its order, without a copy when the kept shared list is
  // the answer as it is (a radius neighbourhood of the lists' own radius); otherwise they are
  // written into scratch.indices (for a smaller radius the indices alone: scratch.sq_dists is
  // then not the answer's). Valid while this object and `scratch` are. Thread-safe.
  std::span<const std::uint32_t> view(std::size_t i, const Neighborhood& hood,
                                      NeighborList& scratch) const;

  // The k nearest of point i among the points with allowed[j] != 0 (the point itself included
  // when allowed), sorted by squared distance, ties by index. False when the shared search was
  // cut by its cap or holds fewer than k allowed points (the k nearest may then lie outside
  // it): the caller then searches itself. Thread-safe.
  bool nearest(std::size_t i, int k, const std::vector<std::uint8_t>& allowed,
               NeighborList& out) const;

 private:
  struct Block {
    std::vector<std::uint32_t> begin;  // per point of the block, into indices, or a state below
    std::vector<std::uint32_t> end;
    std::vector<std::uint32_t> indices;
    std::vector<float> sq_dists;
  };
  // Point i's shared list (kept, or searched again into `scratch`); false when the shared
  // search is cut by its cap at i.
  bool shared(std::size_t i, NeighborList& scratch, const std::uint32_t*& indices,
              const float*& sq_dists, std::size_t& count) const;

  // Searches and keeps, within each block's share of the budget, the lists of the block's
  // points that `take` accepts and that have none yet.
  template <typename Take>
  void fill(const Take& take, std::size_t block_budget, const RunContext& context);

  const std::vector<Vec3f>& points_;
  const NeighborSearch& search_;
  Neighborhood hood_;
  std::size_t kept_points_ = 0;
  std::vector<Block> blocks_;
};

}  // namespace primlabel
