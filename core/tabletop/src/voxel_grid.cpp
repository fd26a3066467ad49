#include "primlabel/tabletop/voxel_grid.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "primlabel/geometry/cancellation.hpp"

namespace primlabel::tabletop {

std::vector<std::uint32_t> finite_indices(const std::vector<Vec3f>& points) {
  std::vector<std::uint32_t> out;
  out.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    if (is_finite(points[i])) out.push_back(static_cast<std::uint32_t>(i));
  return out;
}

namespace {

constexpr std::size_t kCheckEvery = std::size_t(1) << 16;
constexpr const char* kWhat = "voxel downsampling";

// std::sort in runs of 1M elements, then pairwise merges, with a stop check between any two:
// one std::sort of 10M pairs is about a second nobody could interrupt. Same order as std::sort
// (the keys are unique pairs).
template <typename T>
void sort_checked(std::vector<T>& v, const std::stop_token& stop) {
  constexpr std::size_t kRun = std::size_t(1) << 20;
  for (std::size_t first = 0; first < v.size(); first += kRun) {
    throw_if_stopped(stop, kWhat);
    std::sort(v.begin() + first, v.begin() + std::min(v.size(), first + kRun));
  }
  for (std::size_t width = kRun; width < v.size(); width *= 2)
    for (std::size_t first = 0; first + width < v.size(); first += 2 * width) {
      throw_if_stopped(stop, kWhat);
      std::inplace_merge(v.begin() + first, v.begin() + first + width,
                         v.begin() + std::min(v.size(), first + 2 * width));
    }
}

// Stable LSD radix sort of (key, index) pairs by key, 11 bits a pass over the `key_bits` that
// the keys use: 3 passes for a depth frame where std::sort needs ~18 comparisons a pair. With the
// indices ascending on input this is the order std::sort gives the pairs.
void radix_sort_checked(std::vector<std::pair<std::uint64_t, std::uint32_t>>& v, int key_bits,
                        const std::stop_token& stop) {
  constexpr int kDigitBits = 11;
  constexpr std::size_t kBuckets = std::size_t(1) << kDigitBits;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> other(v.size());
  std::vector<std::size_t> counts(kBuckets);
  for (int shift = 0; shift < key_bits; shift += kDigitBits) {
    throw_if_stopped(stop, kWhat);
    std::fill(counts.begin(), counts.end(), 0);
    for (const auto& entry : v) ++counts[(entry.first >> shift) & (kBuckets - 1)];
    std::size_t total = 0;
    for (std::size_t& c : counts) total += std::exchange(c, total);
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (k % kCheckEvery == 0) throw_if_stopped(stop, kWhat);
      other[counts[(v[k].first >> shift) & (kBuckets - 1)]++] = v[k];
    }
    v.swap(other);
  }
}

using KeyedPoints = std::vector<std::pair<std::uint64_t, std::uint32_t>>;

// Cells fit 21 bits an axis (every real scan at any sensible leaf): one 64-bit key per point,
// radix-sorted when the indices ascend.
KeyedPoints packed_cell_keys(const std::vector<Vec3f>& points,
                             const std::vector<std::uint32_t>& indices, const Vec3f& lo,
                             const Vec3f& hi, double inv, const std::stop_token& stop) {
  std::uint64_t cells[3];
  for (int axis = 0; axis < 3; ++axis)
    cells[axis] =
        static_cast<std::uint64_t>(std::floor((double(hi[axis]) - double(lo[axis])) * inv)) + 1;
  KeyedPoints keyed;
  keyed.reserve(indices.size());
  for (std::size_t k = 0; k < indices.size(); ++k) {
    if (k % kCheckEvery == 0) throw_if_stopped(stop, kWhat);
    const std::uint32_t i = indices[k];
    const Vec3f& p = points[i];
    const auto cell = [&](int axis) {
      return std::min(cells[axis] - 1,
                      static_cast<std::uint64_t>(std::floor((double(p[axis]) - lo[axis]) * inv)));
    };
    keyed.emplace_back((cell(2) * cells[1] + cell(1)) * cells[0] + cell(0), i);
  }
  const std::uint64_t largest_key = cells[0] * cells[1] * cells[2] - 1;
  if (std::is_sorted(indices.begin(), indices.end()))
    radix_sort_checked(keyed, std::bit_width(largest_key), stop);
  else
    sort_checked(keyed, stop);
  return keyed;
}

// Any extent (a far outlier, a leaf of 1e-30): the cell coordinates stay doubles, exact integers
// or beyond 2^53 still ordered and apart for distinct float points, and each point's key is its
// cell's rank in (z, y, x) order. The cells start at 0, not at the lowest corner: a far point
// below the scan would otherwise take the scan's precision (1e38 + 0.1 == 1e38).
KeyedPoints ranked_cell_keys(const std::vector<Vec3f>& points,
                             const std::vector<std::uint32_t>& indices, double inv,
                             const std::stop_token& stop) {
  struct Cell {
    double z, y, x;
    std::uint32_t index;
    auto operator<=>(const Cell&) const = default;
  };
  std::vector<Cell> cells;
  cells.reserve(indices.size());
  for (std::size_t k = 0; k < indices.size(); ++k) {
    if (k % kCheckEvery == 0) throw_if_stopped(stop, kWhat);
    const Vec3f& p = points[indices[k]];
    const auto cell = [&](int axis) { return std::floor(double(p[axis]) * inv); };
    cells.push_back({cell(2), cell(1), cell(0), indices[k]});
  }
  sort_checked(cells, stop);
  KeyedPoints keyed;
  keyed.reserve(cells.size());
  std::uint64_t rank = 0;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const Cell& c = cells[k];
    if (k > 0 && (c.z != cells[k - 1].z || c.y != cells[k - 1].y || c.x != cells[k - 1].x)) ++rank;
    keyed.emplace_back(rank, c.index);
  }
  return keyed;
}

}  // namespace

VoxelGrid voxel_downsample(const std::vector<Vec3f>& points,
                           const std::vector<std::uint32_t>& indices, float leaf,
                           const RunContext& context) {
  const std::stop_token& stop = context.stop;
  if (!(leaf > 0.0f) || !std::isfinite(leaf))
    throw std::invalid_argument("voxel leaf must be positive, got " + std::to_string(leaf));
  VoxelGrid grid;
  grid.voxel_of_point.assign(points.size(), kNoVoxel);
  grid.member_offsets.push_back(0);
  if (indices.empty()) return grid;

  Vec3f lo = points[indices[0]];
  Vec3f hi = lo;
  for (std::size_t k = 0; k < indices.size(); ++k) {
    if (k % kCheckEvery == 0) throw_if_stopped(stop, kWhat);
    lo = lo.cwiseMin(points[indices[k]]);
    hi = hi.cwiseMax(points[indices[k]]);
  }
  const double inv = 1.0 / leaf;
  // The extent in double: in float it overflows to infinity for points near +-FLT_MAX.
  const double extent = (hi.cast<double>() - lo.cast<double>()).maxCoeff();
  // Sorting (key, index) pairs makes the voxel order and member order independent of the input.
  // Both keys order cells by (z, y, x); the packed ones count from the cloud's lowest corner.
  constexpr double kPackedCells = double(1 << 21);
  const KeyedPoints keyed = extent * inv < kPackedCells - 1
                                ? packed_cell_keys(points, indices, lo, hi, inv, stop)
                                : ranked_cell_keys(points, indices, inv, stop);

  grid.members.reserve(keyed.size());
  for (std::size_t begin = 0; begin < keyed.size();) {
    throw_if_stopped(stop, kWhat);  // every voxel: cheap next to its members
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
