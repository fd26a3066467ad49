#include "primlabel/ros_common/pointcloud2_xyz.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "primlabel/ros_common/byte_order.hpp"

namespace primlabel::roscommon {

namespace {

CoordinateField coordinate_field(const PointCloud2Layout& cloud, const std::string& name) {
  const auto found = std::find_if(cloud.fields.begin(), cloud.fields.end(),
                                  [&](const PointFieldInfo& f) { return f.name == name; });
  if (found == cloud.fields.end())
    throw std::invalid_argument("the PointCloud2 has no field '" + name + "'");
  if (found->datatype != datatype::kFloat32 && found->datatype != datatype::kFloat64)
    throw std::invalid_argument("field '" + name + "' has datatype " +
                                std::to_string(found->datatype) +
                                "; x, y and z must be FLOAT32 (7) or FLOAT64 (8)");
  CoordinateField field{found->offset, found->datatype == datatype::kFloat64};
  const std::uint64_t end = std::uint64_t(field.offset) + (field.float64 ? 8 : 4);
  if (end > cloud.point_step)
    throw std::invalid_argument("field '" + name + "' at offset " + std::to_string(field.offset) +
                                " does not fit in point_step " + std::to_string(cloud.point_step));
  return field;
}

// One coordinate as float, in this machine's byte order.
float read_coordinate(const std::uint8_t* point, const CoordinateField& field, bool swap) {
  std::uint8_t bytes[8];
  const int size = field.float64 ? 8 : 4;
  std::memcpy(bytes, point + field.offset, size);
  if (swap) std::reverse(bytes, bytes + size);
  if (field.float64) {
    double value;
    std::memcpy(&value, bytes, sizeof value);
    return static_cast<float>(value);
  }
  float value;
  std::memcpy(&value, bytes, sizeof value);
  return value;
}

}  // namespace

XyzLayout xyz_layout(const PointCloud2Layout& cloud, std::size_t data_size) {
  if (cloud.width == 0 || cloud.height == 0)
    throw std::invalid_argument("the PointCloud2 has no points (width " +
                                std::to_string(cloud.width) + ", height " +
                                std::to_string(cloud.height) + ")");
  XyzLayout layout;
  layout.x = coordinate_field(cloud, "x");
  layout.y = coordinate_field(cloud, "y");
  layout.z = coordinate_field(cloud, "z");
  layout.swap_bytes = needs_swap(cloud.is_bigendian);
  // 64-bit arithmetic: width * point_step fits; (height - 1) * row_step is checked by division.
  const std::uint64_t row_bytes = std::uint64_t(cloud.width) * cloud.point_step;
  if (cloud.row_step < row_bytes)
    throw std::invalid_argument(
        "row_step " + std::to_string(cloud.row_step) +
        " is shorter than width * point_step = " + std::to_string(row_bytes));
  const std::uint64_t size = data_size;
  const std::uint64_t rows_before_last = cloud.height - 1;
  if (size < row_bytes ||
      (rows_before_last > 0 && (size - row_bytes) / rows_before_last < cloud.row_step))
    throw std::invalid_argument("data holds " + std::to_string(size) + " bytes, fewer than " +
                                std::to_string(cloud.height) + " rows of row_step " +
                                std::to_string(cloud.row_step));
  return layout;
}

PointCloud xyz_from_pointcloud2(const PointCloud2View& cloud) {
  const XyzLayout layout = xyz_layout(cloud, cloud.data_size);
  PointCloud points;
  points.xyz.resize(std::size_t(cloud.width) * cloud.height);
  points.width = cloud.width;
  points.height = cloud.height;
  std::size_t i = 0;
  for (std::uint32_t row = 0; row < cloud.height; ++row) {
    const std::uint8_t* point = cloud.data + std::size_t(row) * cloud.row_step;
    for (std::uint32_t column = 0; column < cloud.width; ++column, point += cloud.point_step)
      points.xyz[i++] = Vec3f(read_coordinate(point, layout.x, layout.swap_bytes),
                              read_coordinate(point, layout.y, layout.swap_bytes),
                              read_coordinate(point, layout.z, layout.swap_bytes));
  }
  return points;
}

}  // namespace primlabel::roscommon
