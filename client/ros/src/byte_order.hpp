#pragma once
// Whether a PointCloud2's words need swapping here. (The ROS message headers need C++17 (their
// allocator rebind is gone in C++20), so this code cannot use std::endian.)

#include <cstdint>

namespace primlabel::rosnode {

inline constexpr bool kBigEndianHost = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;

// True when a message with this is_bigendian flag is in the other byte order than this machine.
inline constexpr bool needs_swap(std::uint8_t is_bigendian) {
  return (is_bigendian != 0) != kBigEndianHost;
}

}  // namespace primlabel::rosnode
