#pragma once
// The packed little-endian arrays of the labeling API (proto/primlabel/v1/labeling.proto):
// float32 xyz / normals / intensity / descriptors / probabilities and uint32 labels, point-major.
// Header-only, no dependency but the standard library, so the server and the clients share one
// layout (primlabel::api).

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace primlabel::wire {

inline constexpr std::size_t kXyzBytesPerPoint = 3 * sizeof(float);
inline constexpr std::size_t kNormalBytesPerPoint = 3 * sizeof(float);
inline constexpr std::size_t kIntensityBytesPerPoint = sizeof(float);
inline constexpr std::size_t kLabelBytesPerPoint = sizeof(std::uint32_t);

namespace detail {
template <typename T>
T byteswap_value(T value) {
  static_assert(sizeof(T) == 4);
  std::uint32_t bits;
  std::memcpy(&bits, &value, 4);
  bits = (bits >> 24) | ((bits >> 8) & 0xff00u) | ((bits << 8) & 0xff0000u) | (bits << 24);
  std::memcpy(&value, &bits, 4);
  return value;
}
}  // namespace detail

// Appends `values` as little-endian 4-byte words.
template <typename T>
void append_le(std::string& out, std::span<const T> values) {
  static_assert(sizeof(T) == 4 && std::is_trivially_copyable_v<T>);
  const std::size_t offset = out.size();
  out.resize(offset + values.size_bytes());
  if constexpr (std::endian::native == std::endian::little) {
    if (!values.empty()) std::memcpy(out.data() + offset, values.data(), values.size_bytes());
  } else {
    for (std::size_t i = 0; i < values.size(); ++i) {
      const T swapped = detail::byteswap_value(values[i]);
      std::memcpy(out.data() + offset + 4 * i, &swapped, 4);
    }
  }
}

template <typename T>
std::string pack_le(std::span<const T> values) {
  std::string out;
  append_le(out, values);
  return out;
}

// Number of T values in `bytes`, or false when its length is not a multiple of sizeof(T) * group
// (e.g. group 3 for xyz).
template <typename T>
bool count_values(std::string_view bytes, std::size_t group, std::size_t& count) {
  const std::size_t unit = sizeof(T) * group;
  if (bytes.size() % unit != 0) return false;
  count = bytes.size() / sizeof(T);
  return true;
}

// Reads bytes.size() / 4 little-endian words into out (which must have room for them).
template <typename T>
void unpack_le(std::string_view bytes, T* out) {
  static_assert(sizeof(T) == 4 && std::is_trivially_copyable_v<T>);
  const std::size_t count = bytes.size() / 4;
  if constexpr (std::endian::native == std::endian::little) {
    if (count) std::memcpy(out, bytes.data(), count * 4);
  } else {
    for (std::size_t i = 0; i < count; ++i) {
      std::memcpy(&out[i], bytes.data() + 4 * i, 4);
      out[i] = detail::byteswap_value(out[i]);
    }
  }
}

// Points [first, first + count) of `points` as packed float32 triples. Vec3 is any type of three
// packed floats with data() (Eigen's Vector3f, primlabel::Vec3f).
template <typename Vec3>
std::string pack_vec3(const std::vector<Vec3>& points, std::size_t first, std::size_t count) {
  static_assert(sizeof(Vec3) == 3 * sizeof(float));
  if (first > points.size() || count > points.size() - first)
    throw std::out_of_range("pack_vec3: range past the end");
  if (count == 0) return {};
  return pack_le(std::span<const float>(points[first].data(), 3 * count));
}

// Packed float32 triples back into points; throws std::invalid_argument when the length is not a
// multiple of 12 bytes.
template <typename Vec3>
std::vector<Vec3> unpack_vec3(std::string_view bytes) {
  static_assert(sizeof(Vec3) == 3 * sizeof(float));
  if (bytes.size() % kXyzBytesPerPoint != 0)
    throw std::invalid_argument("packed xyz of " + std::to_string(bytes.size()) +
                                " bytes is not a multiple of 12");
  std::vector<Vec3> out(bytes.size() / kXyzBytesPerPoint);
  if (!out.empty()) unpack_le(bytes, out.front().data());
  return out;
}

inline std::string pack_u32(const std::uint32_t* values, std::size_t count) {
  return pack_le(std::span<const std::uint32_t>(values, count));
}

inline std::string pack_f32(const float* values, std::size_t count) {
  return pack_le(std::span<const float>(values, count));
}

// Decodes bytes.size() / 4 values into out[0..); the caller checked the size.
inline void unpack_u32(std::string_view bytes, std::uint32_t* out) { unpack_le(bytes, out); }
inline void unpack_f32(std::string_view bytes, float* out) { unpack_le(bytes, out); }

}  // namespace primlabel::wire
