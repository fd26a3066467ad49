#pragma once
// What ROS 1's and rclcpp's sensor_msgs/PointCloud2 have alike: the layout and the bytes, members
// of the same names in both; their headers differ, so each node converts its header itself.
// Templates over the message type, so the bridge still includes no ROS header.

#include <utility>

#include "primlabel/ros_common/pointcloud2.hpp"

namespace primlabel::roscommon {

// `message`'s layout and bytes as a view, without frame_id and stamp (`message` must outlive it).
template <class Message>
PointCloud2View view_of_body(const Message& message) {
  PointCloud2View view;
  view.height = message.height;
  view.width = message.width;
  for (const auto& f : message.fields)
    view.fields.push_back({f.name, f.offset, f.datatype, f.count});
  view.is_bigendian = message.is_bigendian;
  view.point_step = message.point_step;
  view.row_step = message.row_step;
  view.is_dense = message.is_dense;
  view.data = message.data.data();
  view.data_size = message.data.size();
  return view;
}

// A message of `cloud`'s layout and bytes (moved, not copied); its header is left to the caller.
template <class Message>
Message message_body(PointCloud2Data&& cloud) {
  Message message;
  message.height = cloud.height;
  message.width = cloud.width;
  for (const PointFieldInfo& f : cloud.fields) {
    typename decltype(message.fields)::value_type field;
    field.name = f.name;
    field.offset = f.offset;
    field.datatype = f.datatype;
    field.count = f.count;
    message.fields.push_back(field);
  }
  message.is_bigendian = cloud.is_bigendian;
  message.point_step = cloud.point_step;
  message.row_step = cloud.row_step;
  message.is_dense = cloud.is_dense;
  message.data = std::move(cloud.data);
  return message;
}

}  // namespace primlabel::roscommon
