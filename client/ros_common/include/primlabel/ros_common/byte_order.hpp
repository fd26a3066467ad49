#pragma once
// Whether a PointCloud2's words need swapping here. (C++17, as the ROS 1 message headers need, so
// no std::endian.)

#include <cstdint>

namespace primlabel::roscommon {

inline constexpr bool kBigEndianHost = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;

// True when a message with this is_bigendian flag is in the other byte order than this machine.
inline constexpr bool needs_swap(std::uint8_t is_bigendian) {
  return (is_bigendian != 0) != kBigEndianHost;
}

}  // namespace primlabel::roscommon
