#pragma once
// Exact duplicate points (equal finite coordinates; -0 equals +0). A scan may repeat a point
// many times (or a client may send 100k copies of one); describing each copy costs as much as
// the whole cluster, and a neighbourhood of copies has no plane. label_cloud describes one
// representative per position, the lowest index, and gives every copy its results.

#include <cstdint>
#include <span>
#include <stop_token>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::pipeline {

struct DuplicateMap {
  // Ascending point indices, one per distinct position (non-finite points are their own).
  std::vector<std::uint32_t> representatives;
  // Per point, its representative's position in `representatives`.
  std::vector<std::uint32_t> slot_of;
  bool any() const { return representatives.size() < slot_of.size(); }
};

// O(n) expected time and 8-16 bytes per point (a hash table with a per-call random seed, so no
// input can force its collisions; the result does not depend on the seed). Checks `stop` every
// 64k points and throws Cancelled.
DuplicateMap find_duplicates(const std::vector<Vec3f>& xyz, const std::stop_token& stop = {});

// The same among the points xyz[indices[k]] only, without copying them out: `representatives`
// and `slot_of` then hold positions k in `indices` (with ascending indices a representative is
// still the copy of lowest index).
DuplicateMap find_duplicates(const std::vector<Vec3f>& xyz, std::span<const std::uint32_t> indices,
                             const std::stop_token& stop = {});

}  // namespace primlabel::pipeline
