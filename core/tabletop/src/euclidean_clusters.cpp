#include "primlabel/tabletop/euclidean_clusters.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>

#include "disjoint_sets.hpp"

namespace primlabel::tabletop {

void ClusterOptions::validate() const {
  if (!(tolerance > 0.0f) || !std::isfinite(tolerance))
    throw std::invalid_argument("cluster tolerance must be positive, got " +
                                std::to_string(tolerance));
  if (min_size > max_size)
    throw std::invalid_argument("cluster min size " + std::to_string(min_size) +
                                " exceeds max size " + std::to_string(max_size));
}

namespace {

constexpr int kBits = 21;
constexpr std::int64_t kCells = std::int64_t(1) << kBits;

std::uint64_t pack(std::int64_t x, std::int64_t y, std::int64_t z) {
  return (std::uint64_t(z) << (2 * kBits)) | (std::uint64_t(y) << kBits) | std::uint64_t(x);
}

struct Cell {
  std::uint64_t key;
  std::uint32_t begin, end;  // range in the sorted point order
};

}  // namespace

std::vector<std::vector<std::uint32_t>> euclidean_clusters(
    const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& indices,
    const ClusterOptions& options) {
  options.validate();
  std::vector<std::vector<std::uint32_t>> clusters;
  if (indices.empty()) return clusters;

  // Cells of diagonal just under the tolerance: any two points of one cell are neighbours.
  const double cell = options.tolerance / std::sqrt(3.0) * (1.0 - 1e-6);
  const float sq_tolerance = options.tolerance * options.tolerance;
  Vec3f lo = points[indices[0]], hi = lo;
  for (std::uint32_t i : indices) {
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  if ((hi - lo).maxCoeff() / cell >= double(kCells - 4))
    throw std::invalid_argument("cluster tolerance " + std::to_string(options.tolerance) +
                                " is too small for the extent of the points");

  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(indices.size());
  for (std::uint32_t i : indices) {
    const Vec3f& p = points[i];
    const auto c = [&](int axis) {
      return static_cast<std::int64_t>(std::floor((double(p[axis]) - lo[axis]) / cell));
    };
    keyed.emplace_back(pack(c(0), c(1), c(2)), i);
  }
  std::sort(keyed.begin(), keyed.end());

  std::vector<Cell> cells;
  for (std::uint32_t b = 0; b < keyed.size();) {
    std::uint32_t e = b;
    while (e < keyed.size() && keyed[e].first == keyed[b].first) ++e;
    cells.push_back({keyed[b].first, b, e});
    b = e;
  }
  // Open-addressing hash from cell key to cell: the neighbour lookups dominate otherwise.
  std::size_t slots = 16;
  while (slots < 2 * cells.size()) slots *= 2;
  std::vector<std::uint32_t> table(slots, UINT32_MAX);
  const auto slot_of = [&](std::uint64_t key) {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & (slots - 1);
  };
  for (std::uint32_t c = 0; c < cells.size(); ++c) {
    std::size_t slot = slot_of(cells[c].key);
    while (table[slot] != UINT32_MAX) slot = (slot + 1) & (slots - 1);
    table[slot] = c;
  }
  const auto find_cell = [&](std::uint64_t key) -> const Cell* {
    for (std::size_t slot = slot_of(key);; slot = (slot + 1) & (slots - 1)) {
      if (table[slot] == UINT32_MAX) return nullptr;
      if (cells[table[slot]].key == key) return &cells[table[slot]];
    }
  };

  // Half of the 5x5x5 block (cells two apart can still hold points closer than the tolerance),
  // without the offsets whose boxes are farther apart than the tolerance.
  struct Offset {
    int dx, dy, dz;
  };
  std::vector<Offset> offsets;
  for (int dz = -2; dz <= 2; ++dz)
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        if (std::make_tuple(dz, dy, dx) <= std::make_tuple(0, 0, 0)) continue;
        const auto gap = [](int d) { return std::max(std::abs(d) - 1, 0); };
        const double box_gap =
            cell * std::sqrt(double(gap(dx) * gap(dx) + gap(dy) * gap(dy) + gap(dz) * gap(dz)));
        if (box_gap < options.tolerance) offsets.push_back({dx, dy, dz});
      }

  // Touching cells first: they link at the first close pair. By the time the cells two apart are
  // visited they are mostly joined already through a common neighbour and need no test.
  std::stable_sort(offsets.begin(), offsets.end(), [](const Offset& a, const Offset& b) {
    const auto far = [](const Offset& o) {
      return std::abs(o.dx) > 1 || std::abs(o.dy) > 1 || std::abs(o.dz) > 1;
    };
    return !far(a) && far(b);
  });
  const std::size_t touching = static_cast<std::size_t>(std::find_if(offsets.begin(), offsets.end(),
                                                                     [](const Offset& o) {
                                                                       return std::abs(o.dx) > 1 ||
                                                                              std::abs(o.dy) > 1 ||
                                                                              std::abs(o.dz) > 1;
                                                                     }) -
                                                        offsets.begin());

  DisjointSets sets(cells.size());
  const std::uint64_t mask = kCells - 1;
  const auto link_cells = [&](std::size_t first_offset, std::size_t end_offset) {
    for (std::uint32_t a = 0; a < cells.size(); ++a) {
      const std::int64_t x = cells[a].key & mask, y = (cells[a].key >> kBits) & mask,
                         z = cells[a].key >> (2 * kBits);
      for (std::size_t k = first_offset; k < end_offset; ++k) {
        const Offset& o = offsets[k];
        const std::int64_t nx = x + o.dx, ny = y + o.dy, nz = z + o.dz;
        if (nx < 0 || ny < 0 || nz < 0) continue;
        const Cell* other = find_cell(pack(nx, ny, nz));
        if (!other) continue;
        const auto b = static_cast<std::uint32_t>(other - cells.data());
        if (sets.find(a) == sets.find(b)) continue;
        bool linked = false;
        for (std::uint32_t i = cells[a].begin; i < cells[a].end && !linked; ++i) {
          const Vec3f& p = points[keyed[i].second];
          for (std::uint32_t j = other->begin; j < other->end; ++j)
            if ((points[keyed[j].second] - p).squaredNorm() < sq_tolerance) {
              linked = true;
              break;
            }
        }
        if (linked) sets.join(a, b);
      }
    }
  };
  link_cells(0, touching);
  link_cells(touching, offsets.size());

  // Gather components (roots are the smallest cell index of each component).
  std::vector<std::uint32_t> cluster_of_root(cells.size(), UINT32_MAX);
  for (std::uint32_t c = 0; c < cells.size(); ++c) {
    const std::uint32_t root = sets.find(c);
    if (cluster_of_root[root] == UINT32_MAX) {
      cluster_of_root[root] = static_cast<std::uint32_t>(clusters.size());
      clusters.emplace_back();
    }
    auto& members = clusters[cluster_of_root[root]];
    for (std::uint32_t i = cells[c].begin; i < cells[c].end; ++i)
      members.push_back(keyed[i].second);
  }
  std::erase_if(clusters, [&](const std::vector<std::uint32_t>& c) {
    return c.size() < options.min_size || c.size() > options.max_size;
  });
  for (auto& c : clusters) std::sort(c.begin(), c.end());
  std::sort(clusters.begin(), clusters.end(), [](const auto& a, const auto& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  return clusters;
}

}  // namespace primlabel::tabletop
