#include "primlabel/ros2/pointcloud2_dds.hpp"

namespace primlabel::ros2node {

namespace {

constexpr std::uint64_t kNanosecondsPerSecond = 1'000'000'000;

// The C types take char*, never written through by dds_write.
char* c_string(const std::string& text) { return const_cast<char*>(text.c_str()); }

}  // namespace

std::uint64_t stamp_ns(const builtin_interfaces_msg_dds__Time_& stamp) {
  if (stamp.sec < 0) return 0;
  return std::uint64_t(stamp.sec) * kNanosecondsPerSecond + stamp.nanosec;
}

builtin_interfaces_msg_dds__Time_ ros2_time(std::uint64_t stamp_ns) {
  builtin_interfaces_msg_dds__Time_ time{};
  time.sec = static_cast<std::int32_t>(stamp_ns / kNanosecondsPerSecond);
  time.nanosec = static_cast<std::uint32_t>(stamp_ns % kNanosecondsPerSecond);
  return time;
}

roscommon::PointCloud2View view_of(const sensor_msgs_msg_dds__PointCloud2_& m) {
  roscommon::PointCloud2View view;
  view.frame_id = m.header.frame_id ? m.header.frame_id : "";
  view.stamp_ns = stamp_ns(m.header.stamp);
  view.height = m.height;
  view.width = m.width;
  for (std::uint32_t k = 0; k < m.fields._length; ++k) {
    const sensor_msgs_msg_dds__PointField_& f = m.fields._buffer[k];
    view.fields.push_back({f.name ? f.name : "", f.offset, f.datatype, f.count});
  }
  view.is_bigendian = m.is_bigendian;
  view.point_step = m.point_step;
  view.row_step = m.row_step;
  view.is_dense = m.is_dense;
  view.data = m.data._buffer;
  view.data_size = m.data._buffer ? m.data._length : 0;
  return view;
}

OutgoingPointCloud2::OutgoingPointCloud2(const roscommon::PointCloud2Data& cloud) {
  for (const roscommon::PointFieldInfo& f : cloud.fields) {
    sensor_msgs_msg_dds__PointField_ field{};
    field.name = c_string(f.name);
    field.offset = f.offset;
    field.datatype = f.datatype;
    field.count = f.count;
    fields_.push_back(field);
  }
  message_.header.stamp = ros2_time(cloud.stamp_ns);
  message_.header.frame_id = c_string(cloud.frame_id);
  message_.height = cloud.height;
  message_.width = cloud.width;
  message_.fields._length = message_.fields._maximum = static_cast<std::uint32_t>(fields_.size());
  message_.fields._buffer = fields_.data();
  message_.fields._release = false;
  message_.is_bigendian = cloud.is_bigendian;
  message_.point_step = cloud.point_step;
  message_.row_step = cloud.row_step;
  message_.data._length = message_.data._maximum = static_cast<std::uint32_t>(cloud.data.size());
  message_.data._buffer = const_cast<std::uint8_t*>(cloud.data.data());
  message_.data._release = false;
  message_.is_dense = cloud.is_dense;
}

}  // namespace primlabel::ros2node
