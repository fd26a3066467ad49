#pragma once
// The points of a ROS 1 sensor_msgs/PointCloud2, read by the shared bridge
// (ros_common/pointcloud2_xyz.hpp: the layout rules and what it refuses).

#include <sensor_msgs/PointCloud2.h>

#include "primlabel/geometry/point_cloud.hpp"
#include "ros_common/pointcloud2_xyz.hpp"

namespace primlabel::rosnode {

using roscommon::CoordinateField;
using roscommon::XyzLayout;

// As roscommon::xyz_layout and xyz_from_pointcloud2 on the message.
XyzLayout xyz_layout(const sensor_msgs::PointCloud2& cloud);
PointCloud xyz_from_pointcloud2(const sensor_msgs::PointCloud2& cloud);

}  // namespace primlabel::rosnode
