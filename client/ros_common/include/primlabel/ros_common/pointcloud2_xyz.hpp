#pragma once
// The points of a PointCloud2 read straight from its layout (the x, y and z fields' offsets and
// datatypes, point_step, row_step, is_bigendian), without a PCL round trip, so a robot's cloud of
// any point type is labeled as it arrives.

#include <cstdint>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/ros_common/pointcloud2.hpp"

namespace primlabel::roscommon {

// Where one coordinate sits inside a point.
struct CoordinateField {
  std::uint32_t offset = 0;
  bool float64 = false;  // FLOAT64, else FLOAT32
};

struct XyzLayout {
  CoordinateField x, y, z;
  bool swap_bytes = false;  // is_bigendian differs from this machine's byte order
};

// The layout of x, y and z in `cloud`, checked against its sizes (`data_size` bytes). Throws
// std::invalid_argument naming the problem: no points, a missing x/y/z field, one that is neither
// FLOAT32 nor FLOAT64 or lies outside point_step, a row_step shorter than a row, data shorter
// than its rows.
XyzLayout xyz_layout(const PointCloud2Layout& cloud, std::size_t data_size);

// The points of `cloud` in row-major order (point index = row * width + column), width and
// height kept, so an organised cloud stays organised; NaN points (an organised cloud's invalid
// pixels) stay NaN and the service labels them 0. Viewpoint: the frame's origin (a sensor frame).
// Throws as xyz_layout.
PointCloud xyz_from_pointcloud2(const PointCloud2View& cloud);

}  // namespace primlabel::roscommon
