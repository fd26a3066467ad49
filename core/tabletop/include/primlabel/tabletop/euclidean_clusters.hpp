#pragma once
// Euclidean clustering (connected components of the "closer than tolerance" graph), as PCL's
// EuclideanClusterExtraction, computed on a uniform grid of cells of diagonal `tolerance`: all
// points of one cell are connected, so only pairs of neighbouring cells that are not yet joined
// need a point-to-point test. Exact, and linear in practice.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::tabletop {

struct ClusterOptions {
  float tolerance = 0.02f;  // points closer than this (m) are in the same cluster
  std::size_t min_size = 1;
  std::size_t max_size = std::numeric_limits<std::size_t>::max();

  void validate() const;  // throws std::invalid_argument naming the bad option
};

// Clusters of points[indices] (all finite) with min_size <= size <= max_size. Each cluster lists
// input indices ascending; clusters are ordered by size, largest first, ties by first index.
std::vector<std::vector<std::uint32_t>> euclidean_clusters(
    const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& indices,
    const ClusterOptions& options);

}  // namespace primlabel::tabletop
