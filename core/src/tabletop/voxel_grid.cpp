#include "primlabel/tabletop/voxel_grid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace primlabel::tabletop {

std::vector<std::uint32_t> finite_indices(const std::vector<Vec3f>& points) {
  std::vector<std::uint32_t> out;
  out.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    if (is_finite(points[i])) out.push_back(static_cast<std::uint32_t>(i));
  return out;
}

VoxelGrid voxel_downsample(const std::vector<Vec3f>& points,
                           const std::vector<std::uint32_t>& indices, float leaf) {
  if (!(leaf > 0.0f) || !std::isfinite(leaf))
    throw std::invalid_argument("voxel leaf must be positive, got " + std::to_string(leaf));
  VoxelGrid grid;
  grid.voxel_of_point.assign(points.size(), kNoVoxel);
  grid.member_offsets.push_back(0);
  if (indices.empty()) return grid;

  Vec3f lo = points[indices[0]];
  Vec3f hi = lo;
  for (std::uint32_t i : indices) {
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  const double inv = 1.0 / leaf;
  constexpr double kMaxCells = double(1 << 21);
  if ((hi - lo).maxCoeff() * inv >= kMaxCells - 1)
    throw std::invalid_argument("voxel leaf " + std::to_string(leaf) +
                                " is too small for the cloud's extent");

  // Sorting (key, index) pairs makes the voxel order and member order independent of the input.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(indices.size());
  for (std::uint32_t i : indices) {
    const Vec3f& p = points[i];
    const auto cell = [&](int axis) {
      return static_cast<std::uint64_t>(std::floor((double(p[axis]) - lo[axis]) * inv));
    };
    keyed.emplace_back((cell(2) << 42) | (cell(1) << 21) | cell(0), i);
  }
  std::sort(keyed.begin(), keyed.end());

  grid.members.reserve(keyed.size());
  for (std::size_t begin = 0; begin < keyed.size();) {
    std::size_t end = begin;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    const auto voxel = static_cast<std::uint32_t>(grid.centroids.size());
    while (end < keyed.size() && keyed[end].first == keyed[begin].first) {
      const std::uint32_t i = keyed[end].second;
      sum += points[i].cast<double>();
      grid.members.push_back(i);
      grid.voxel_of_point[i] = voxel;
      ++end;
    }
    grid.centroids.push_back((sum / double(end - begin)).cast<float>());
    grid.member_offsets.push_back(static_cast<std::uint32_t>(grid.members.size()));
    begin = end;
  }
  return grid;
}

}  // namespace primlabel::tabletop
