#pragma once
// sensor_msgs/msg/PointCloud2 as the C type idlc generates from idl/ (the ROS 2 wire type
// sensor_msgs::msg::dds_::PointCloud2_) to and from the shared bridge's PointCloud2View and
// PointCloud2Data (ros_common/pointcloud2.hpp).

#include <cstdint>
#include <vector>

#include "primlabel/ros_common/pointcloud2.hpp"
#include "sensor_msgs/msg/PointCloud2.h"
#include "std_msgs/msg/Header.h"

namespace primlabel::ros2node {

// builtin_interfaces/Time in nanoseconds since the epoch; a time before it is 0.
std::uint64_t stamp_ns(const builtin_interfaces_msg_dds__Time_& stamp);
builtin_interfaces_msg_dds__Time_ ros2_time(std::uint64_t stamp_ns);

// A view of `message` (a taken sample): its layout copied, its bytes not.
roscommon::PointCloud2View view_of(const sensor_msgs_msg_dds__PointCloud2_& message);

// A message for dds_write that points into `cloud` (its frame_id, field names and bytes):
// valid while `cloud` lives unchanged; dds_write copies what it sends.
class OutgoingPointCloud2 {
 public:
  explicit OutgoingPointCloud2(const roscommon::PointCloud2Data& cloud);
  OutgoingPointCloud2(const OutgoingPointCloud2&) = delete;
  OutgoingPointCloud2& operator=(const OutgoingPointCloud2&) = delete;
  const sensor_msgs_msg_dds__PointCloud2_* message() const { return &message_; }

 private:
  std::vector<sensor_msgs_msg_dds__PointField_> fields_;
  sensor_msgs_msg_dds__PointCloud2_ message_{};
};

}  // namespace primlabel::ros2node
