#include "primlabel/pipeline/duplicates.hpp"

#include <bit>
#include <limits>
#include <random>
#include <stdexcept>

#include "primlabel/geometry/cancellation.hpp"

namespace primlabel::pipeline {

namespace {

constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
constexpr std::size_t kCheckEvery = std::size_t(1) << 16;

// The bits of a coordinate, with -0 folded onto +0 so that equal floats get equal keys.
std::uint32_t key_bits(float v) { return std::bit_cast<std::uint32_t>(v + 0.0f); }

// A keyed 64-bit mix (splitmix64's finaliser around a random seed).
std::uint64_t mix(std::uint64_t h) {
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  return h ^ (h >> 31);
}

// The duplicate map of the points point(0) .. point(n - 1).
template <typename PointAt>
DuplicateMap find_duplicates_of(std::size_t n, const PointAt& point, const std::stop_token& stop) {
  if (n >= kEmpty) throw std::invalid_argument("find_duplicates: more than 2^32-2 points");
  DuplicateMap map;
  map.slot_of.resize(n);
  std::size_t slots = 16;
  while (slots < 2 * n) slots *= 2;
  std::vector<std::uint32_t> table(slots, kEmpty);  // representative point index per slot
  const std::uint64_t seed = (std::uint64_t(std::random_device{}()) << 32) ^ std::random_device{}();
  for (std::size_t i = 0; i < n; ++i) {
    if (i % kCheckEvery == 0) throw_if_stopped(stop, "finding duplicate points");
    const Vec3f& p = point(i);
    if (!is_finite(p)) {  // never equal to anything: its own representative
      map.slot_of[i] = static_cast<std::uint32_t>(map.representatives.size());
      map.representatives.push_back(static_cast<std::uint32_t>(i));
      continue;
    }
    const std::uint32_t bx = key_bits(p.x()), by = key_bits(p.y()), bz = key_bits(p.z());
    std::uint64_t h = mix(seed ^ ((std::uint64_t(bx) << 32) | by));
    h = mix(h ^ bz);
    std::size_t slot = h & (slots - 1);
    while (table[slot] != kEmpty) {
      const std::uint32_t j = table[slot];
      if (point(j) == p) break;  // float equality: -0 == +0
      slot = (slot + 1) & (slots - 1);
    }
    if (table[slot] == kEmpty) {
      table[slot] = static_cast<std::uint32_t>(i);
      // Points arrive in index order, so the first of each position is the lowest index; its
      // slot in `representatives` is stored in slot_of[i] and found again through the point.
      map.slot_of[i] = static_cast<std::uint32_t>(map.representatives.size());
      map.representatives.push_back(static_cast<std::uint32_t>(i));
    } else {
      map.slot_of[i] = map.slot_of[table[slot]];
    }
  }
  return map;
}

}  // namespace

DuplicateMap find_duplicates(const std::vector<Vec3f>& xyz, const std::stop_token& stop) {
  return find_duplicates_of(
      xyz.size(), [&](std::size_t i) -> const Vec3f& { return xyz[i]; }, stop);
}

DuplicateMap find_duplicates(const std::vector<Vec3f>& xyz, std::span<const std::uint32_t> indices,
                             const std::stop_token& stop) {
  return find_duplicates_of(
      indices.size(), [&](std::size_t k) -> const Vec3f& { return xyz[indices[k]]; }, stop);
}

}  // namespace primlabel::pipeline
