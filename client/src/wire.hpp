#pragma once
// The client's view of the packed little-endian arrays (proto/primlabel/v1/labeling.proto): point
// coordinates, labels, descriptors and probabilities, built on the packing the server shares
// (primlabel_wire, server/wire), with the size checks the client needs.

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "primlabel/core/point_cloud.hpp"
#include "primlabel/wire/packing.hpp"

namespace primlabel::client::wire {

inline constexpr std::size_t kXyzBytes = primlabel::wire::kXyzBytesPerPoint;
inline constexpr std::size_t kLabelBytes = primlabel::wire::kLabelBytesPerPoint;

// Eigen's Vector3f is three packed floats, so a run of points is a run of floats.
static_assert(sizeof(Vec3f) == 3 * sizeof(float));

// Points [first, first + count) of `points` as packed float32 triples.
inline std::string pack_vec3(const std::vector<Vec3f>& points, std::size_t first,
                             std::size_t count) {
  if (first > points.size() || count > points.size() - first)
    throw std::out_of_range("pack_vec3: range past the end");
  if (count == 0) return {};
  return primlabel::wire::pack_le(std::span<const float>(points[first].data(), 3 * count));
}

inline std::vector<Vec3f> unpack_vec3(std::string_view bytes) {
  if (bytes.size() % kXyzBytes != 0)
    throw std::invalid_argument("packed xyz of " + std::to_string(bytes.size()) +
                                " bytes is not a multiple of 12");
  std::vector<Vec3f> out(bytes.size() / kXyzBytes);
  if (!out.empty()) primlabel::wire::unpack_le(bytes, out.front().data());
  return out;
}

inline std::string pack_u32(const std::uint32_t* values, std::size_t count) {
  return primlabel::wire::pack_le(std::span<const std::uint32_t>(values, count));
}

inline std::string pack_f32(const float* values, std::size_t count) {
  return primlabel::wire::pack_le(std::span<const float>(values, count));
}

// Decodes bytes.size() / 4 values into out[0..); the caller checked the size.
inline void unpack_u32(std::string_view bytes, std::uint32_t* out) {
  primlabel::wire::unpack_le(bytes, out);
}

inline void unpack_f32(std::string_view bytes, float* out) {
  primlabel::wire::unpack_le(bytes, out);
}

}  // namespace primlabel::client::wire
