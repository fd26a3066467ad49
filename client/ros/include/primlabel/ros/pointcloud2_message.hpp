#pragma once
// sensor_msgs/PointCloud2 (ROS 1) to and from the shared bridge (primlabel/ros_common/): its
// PointCloud2View and PointCloud2Data (pointcloud2.hpp), the points it reads (pointcloud2_xyz.hpp:
// the layout rules and what it refuses) and the labeled cloud it makes (labeled_pointcloud2.hpp:
// the fields appended, the layout kept), with ROS 1's header.

#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include "primlabel/client/client.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/ros_common/labeled_pointcloud2.hpp"
#include "primlabel/ros_common/pointcloud2.hpp"
#include "primlabel/ros_common/pointcloud2_xyz.hpp"

namespace primlabel::rosnode {

// A view of `cloud`: its layout copied, its bytes not (`cloud` must outlive the view).
roscommon::PointCloud2View view_of(const sensor_msgs::PointCloud2& cloud);

// `cloud` as a message with `header` (the caller's: ROS 1's seq has no place in the bridge);
// its bytes are moved, not copied.
sensor_msgs::PointCloud2 to_message(roscommon::PointCloud2Data&& cloud,
                                    const std_msgs::Header& header);

// As roscommon::xyz_layout and xyz_from_pointcloud2 on the message.
roscommon::XyzLayout xyz_layout(const sensor_msgs::PointCloud2& cloud);
PointCloud xyz_from_pointcloud2(const sensor_msgs::PointCloud2& cloud);

// The header the labeled cloud carries: the frame_id and stamp the service echoed, or the
// input's when the service echoed neither (a server older than the echo); the input's seq.
std_msgs::Header echoed_header(const std_msgs::Header& input, const v1::LabelSummary& summary);

// roscommon::labeled_pointcloud2 on the message, with echoed_header.
sensor_msgs::PointCloud2 labeled_pointcloud2(const sensor_msgs::PointCloud2& input,
                                             const client::LabelResult& result,
                                             const roscommon::LabeledFields& fields);

}  // namespace primlabel::rosnode
