#pragma once
// The packed little-endian arrays of the labeling protocol (proto/primlabel/v1/labeling.proto):
// float32 xyz / normals / descriptors / probabilities and uint32 labels, point-major.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "primlabel/core/point_cloud.hpp"

namespace primlabel::client::wire {

inline constexpr std::size_t kXyzBytes = 12;  // float32 x, y, z per point
inline constexpr std::size_t kLabelBytes = 4;

static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559);

namespace detail {
inline std::uint32_t to_little(std::uint32_t v) {
  if constexpr (std::endian::native == std::endian::little) return v;
  return ((v & 0xFFu) << 24) | ((v & 0xFF00u) << 8) | ((v >> 8) & 0xFF00u) | (v >> 24);
}
inline void put_u32(char* out, std::uint32_t v) {
  v = to_little(v);
  std::memcpy(out, &v, 4);
}
inline std::uint32_t get_u32(const char* in) {
  std::uint32_t v;
  std::memcpy(&v, in, 4);
  return to_little(v);  // the swap is its own inverse
}
}  // namespace detail

// Points [first, first + count) of `points` as packed float32 triples.
inline std::string pack_vec3(const std::vector<Vec3f>& points, std::size_t first,
                             std::size_t count) {
  if (first + count > points.size()) throw std::out_of_range("pack_vec3: range past the end");
  std::string out(count * kXyzBytes, '\0');
  char* p = out.data();
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3f& v = points[first + i];
    for (int k = 0; k < 3; ++k, p += 4) detail::put_u32(p, std::bit_cast<std::uint32_t>(v[k]));
  }
  return out;
}

inline std::vector<Vec3f> unpack_vec3(std::string_view bytes) {
  if (bytes.size() % kXyzBytes != 0)
    throw std::invalid_argument("packed xyz of " + std::to_string(bytes.size()) +
                                " bytes is not a multiple of 12");
  std::vector<Vec3f> out(bytes.size() / kXyzBytes);
  const char* p = bytes.data();
  for (auto& v : out)
    for (int k = 0; k < 3; ++k, p += 4) v[k] = std::bit_cast<float>(detail::get_u32(p));
  return out;
}

inline std::string pack_u32(const std::uint32_t* values, std::size_t count) {
  std::string out(count * 4, '\0');
  for (std::size_t i = 0; i < count; ++i) detail::put_u32(out.data() + 4 * i, values[i]);
  return out;
}

inline std::string pack_f32(const float* values, std::size_t count) {
  std::string out(count * 4, '\0');
  for (std::size_t i = 0; i < count; ++i)
    detail::put_u32(out.data() + 4 * i, std::bit_cast<std::uint32_t>(values[i]));
  return out;
}

// Decodes bytes.size() / 4 values into out[0..); the caller checked the size.
inline void unpack_u32(std::string_view bytes, std::uint32_t* out) {
  for (std::size_t i = 0; i < bytes.size() / 4; ++i) out[i] = detail::get_u32(bytes.data() + 4 * i);
}

inline void unpack_f32(std::string_view bytes, float* out) {
  for (std::size_t i = 0; i < bytes.size() / 4; ++i)
    out[i] = std::bit_cast<float>(detail::get_u32(bytes.data() + 4 * i));
}

}  // namespace primlabel::client::wire
