#pragma once
// A sensor_msgs/PointCloud2 as the labeling bridge sees it, whatever middleware carried it (ROS 1
// roscpp, ROS 2 over DDS, rclcpp): the header's frame and stamp, the layout and the bytes. Each
// node converts its own message type to and from these, so the bridge knows no ROS headers.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace primlabel::roscommon {

// sensor_msgs/PointField's datatype constants (the same numbers in ROS 1 and ROS 2).
namespace datatype {
inline constexpr std::uint8_t kInt8 = 1, kUint8 = 2, kInt16 = 3, kUint16 = 4, kInt32 = 5,
                              kUint32 = 6, kFloat32 = 7, kFloat64 = 8;
}  // namespace datatype

struct PointFieldInfo {
  std::string name;
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;
  std::uint32_t count = 1;
};

// Everything but the bytes.
struct PointCloud2Layout {
  std::string frame_id;
  std::uint64_t stamp_ns = 0;  // the header's stamp in nanoseconds since the epoch
  std::uint32_t height = 0, width = 0;
  std::vector<PointFieldInfo> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0, row_step = 0;
  bool is_dense = false;
};

// An incoming cloud: its bytes stay in the middleware's message (no copy).
struct PointCloud2View : PointCloud2Layout {
  const std::uint8_t* data = nullptr;
  std::size_t data_size = 0;
};

// An outgoing cloud, owning its bytes.
struct PointCloud2Data : PointCloud2Layout {
  std::vector<std::uint8_t> data;
};

}  // namespace primlabel::roscommon
