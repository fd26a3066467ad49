#pragma once
// Shared plumbing of the histogram descriptors: which points take part, and each point's
// neighbourhood restricted to points that have a normal.

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::detail {

// A point takes part in descriptors when both its position and its normal are finite.
inline std::vector<char> usable_points(const PointCloud& cloud, const char* descriptor) {
  if (cloud.normals.size() != cloud.size())
    throw std::invalid_argument(std::string(descriptor) +
                                ": the cloud has no normals (estimate them first)");
  std::vector<char> usable(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    usable[i] = is_finite(cloud.xyz[i]) && is_finite(cloud.normals[i]);
  return usable;
}

// `out` without the points lacking a normal.
inline void keep_usable(const std::vector<char>& usable, NeighborList& out) {
  std::size_t kept = 0;
  for (std::size_t j = 0; j < out.size(); ++j) {
    if (!usable[out.indices[j]]) continue;
    out.indices[kept] = out.indices[j];
    out.sq_dists[kept] = out.sq_dists[j];
    ++kept;
  }
  out.indices.resize(kept);
  out.sq_dists.resize(kept);
}

// Neighbours of point `i`, without those lacking a normal.
inline void usable_neighbors(const NeighborSearch& search, const PointCloud& cloud,
                             const std::vector<char>& usable, std::size_t i,
                             const Neighborhood& hood, bool sorted, NeighborList& out) {
  search.find(cloud.xyz[i], hood, out, sorted);
  keep_usable(usable, out);
}

inline const NeighborSearch& ensure_search(const PointCloud& cloud, const NeighborSearch* given,
                                           std::unique_ptr<NeighborSearch>& owned,
                                           const std::stop_token& stop = {}) {
  if (given) return *given;
  owned = std::make_unique<NeighborSearch>(cloud.xyz, stop);
  return *owned;
}

}  // namespace primlabel::detail
