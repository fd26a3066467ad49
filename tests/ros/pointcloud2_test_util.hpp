#pragma once
// PointCloud2 messages for the ROS tests, laid out as robots send them (PCL-style padding after
// x y z, optional row padding, FLOAT32 or FLOAT64 coordinates, either byte order), and readers
// of one field of one point.

#include <sensor_msgs/PointCloud2.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/ros_common/byte_order.hpp"

namespace primlabel::rostest {

using sensor_msgs::PointCloud2;
using sensor_msgs::PointField;

struct MessageLayout {
  bool float64 = false;           // FLOAT64 x y z
  bool big_endian = false;        // is_bigendian, every word swapped
  std::uint32_t row_padding = 0;  // bytes after each row (row_step > width * point_step)
};

// (C++17 here, as the ROS headers need: no designated initializers.)
inline MessageLayout layout_of(bool float64, bool big_endian, std::uint32_t row_padding) {
  MessageLayout layout;
  layout.float64 = float64, layout.big_endian = big_endian, layout.row_padding = row_padding;
  return layout;
}

inline bool swapped(const PointCloud2& m) { return roscommon::needs_swap(m.is_bigendian); }

template <class T>
void put(std::uint8_t* at, T value, bool swap) {
  std::uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (swap) std::reverse(bytes, bytes + sizeof(T));
  std::memcpy(at, bytes, sizeof(T));
}

template <class T>
T get(const std::uint8_t* at, bool swap) {
  std::uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, at, sizeof(T));
  if (swap) std::reverse(bytes, bytes + sizeof(T));
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

// `cloud` (xyz and every attribute it has: normals, curvature, label, rgba, float fields) as
// one message, width and height kept.
inline PointCloud2 to_pointcloud2(const PointCloud& cloud, const MessageLayout& layout = {}) {
  PointCloud2 m;
  m.width = cloud.width;
  m.height = cloud.height;
  m.is_bigendian = layout.big_endian;
  m.is_dense = count_finite(cloud) == cloud.size();
  std::uint32_t offset = 0;
  auto add = [&](const std::string& name, std::uint8_t type, std::uint32_t size) {
    PointField f;
    f.name = name, f.offset = offset, f.datatype = type, f.count = 1;
    m.fields.push_back(f);
    offset += size;
  };
  const std::uint8_t coordinate = layout.float64 ? PointField::FLOAT64 : PointField::FLOAT32;
  const std::uint32_t coordinate_size = layout.float64 ? 8 : 4;
  for (const char* name : {"x", "y", "z"}) add(name, coordinate, coordinate_size);
  offset += 4;  // PCL's padding after x y z
  if (cloud.has_normals())
    for (const char* name : {"normal_x", "normal_y", "normal_z"}) add(name, PointField::FLOAT32, 4);
  if (cloud.has_curvature()) add("curvature", PointField::FLOAT32, 4);
  if (cloud.has_labels()) add("label", PointField::UINT32, 4);
  if (cloud.has_rgba()) add("rgba", PointField::UINT32, 4);
  for (const FloatField& f : cloud.fields)
    for (int k = 0; k < f.count; ++k)
      add(f.count == 1 ? f.name : f.name + "_" + std::to_string(k), PointField::FLOAT32, 4);
  m.point_step = offset;
  m.row_step = m.width * m.point_step + layout.row_padding;
  m.data.assign(std::size_t(m.row_step) * m.height, 0xAB);  // padding bytes are not zero
  const bool swap = swapped(m);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    std::uint8_t* p =
        m.data.data() + (i / m.width) * std::size_t(m.row_step) + (i % m.width) * m.point_step;
    std::size_t field = 0;
    for (int k = 0; k < 3; ++k) {
      std::uint8_t* at = p + m.fields[field++].offset;
      if (layout.float64)
        put<double>(at, cloud.xyz[i][k], swap);
      else
        put<float>(at, cloud.xyz[i][k], swap);
    }
    if (cloud.has_normals())
      for (int k = 0; k < 3; ++k)
        put<float>(p + m.fields[field++].offset, cloud.normals[i][k], swap);
    if (cloud.has_curvature()) put<float>(p + m.fields[field++].offset, cloud.curvature[i], swap);
    if (cloud.has_labels()) put<std::uint32_t>(p + m.fields[field++].offset, cloud.labels[i], swap);
    if (cloud.has_rgba()) put<std::uint32_t>(p + m.fields[field++].offset, cloud.rgba[i], swap);
    for (const FloatField& f : cloud.fields)
      for (int k = 0; k < f.count; ++k) put<float>(p + m.fields[field++].offset, f.row(i)[k], swap);
  }
  return m;
}

inline const PointField& field_named(const PointCloud2& m, const std::string& name) {
  for (const PointField& f : m.fields)
    if (f.name == name) return f;
  throw std::out_of_range("no field " + name);
}

inline bool has_field(const PointCloud2& m, const std::string& name) {
  return std::any_of(m.fields.begin(), m.fields.end(),
                     [&](const PointField& f) { return f.name == name; });
}

inline const std::uint8_t* point_bytes(const PointCloud2& m, std::size_t i) {
  return m.data.data() + (i / m.width) * std::size_t(m.row_step) + (i % m.width) * m.point_step;
}

// Field `name` of point i (row-major index), in this machine's byte order.
template <class T>
T value_of(const PointCloud2& m, std::size_t i, const std::string& name) {
  return get<T>(point_bytes(m, i) + field_named(m, name).offset, swapped(m));
}

}  // namespace primlabel::rostest
