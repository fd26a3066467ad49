#pragma once
// sensor_msgs/PointCloud2 (ROS 1) to and from the shared bridge's PointCloud2View and
// PointCloud2Data (ros_common/pointcloud2.hpp).

#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include "ros_common/pointcloud2.hpp"

namespace primlabel::rosnode {

// A view of `cloud`: its layout copied, its bytes not (`cloud` must outlive the view).
roscommon::PointCloud2View view_of(const sensor_msgs::PointCloud2& cloud);

// `cloud` as a message with `header` (the caller's: ROS 1's seq has no place in the bridge);
// its bytes are moved, not copied.
sensor_msgs::PointCloud2 to_message(roscommon::PointCloud2Data&& cloud,
                                    const std_msgs::Header& header);

}  // namespace primlabel::rosnode
