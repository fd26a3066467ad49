#pragma once
// Removal of invalid points and optional voxel-grid downsampling (one centroid per occupied
// voxel, as PCL's VoxelGrid), keeping the map from every input point to its voxel so results on
// the downsampled points can be carried back to the input.

#include <cstdint>
#include <limits>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::tabletop {

inline constexpr std::uint32_t kNoVoxel = std::numeric_limits<std::uint32_t>::max();

// Indices of the points with finite coordinates, ascending.
std::vector<std::uint32_t> finite_indices(const std::vector<Vec3f>& points);

struct VoxelGrid {
  std::vector<Vec3f> centroids;               // one per occupied voxel
  std::vector<std::uint32_t> voxel_of_point;  // per input point; kNoVoxel when not in `indices`
  std::vector<std::uint32_t> member_offsets;  // voxel v holds members[offsets[v] .. offsets[v+1])
  std::vector<std::uint32_t> members;         // input indices, ascending within each voxel
};

// Centroid per voxel of edge `leaf` over points[indices] (which must be finite). Voxels are
// ordered by their integer coordinates (z, then y, then x), so the output does not depend on the
// order of `indices`. Cells count from the cloud's lowest corner while the extent fits 2^21 of
// them an axis; beyond (a far outlier, a tiny leaf) from the origin, so a far point is a voxel of
// its own and cannot coarsen the scan's. Throws std::invalid_argument when leaf is not positive and
// finite, and Cancelled when context.stop is requested (checked every 64k points and between the
// sort's runs and merges).
VoxelGrid voxel_downsample(const std::vector<Vec3f>& points,
                           const std::vector<std::uint32_t>& indices, float leaf,
                           const RunContext& context = {});

}  // namespace primlabel::tabletop
