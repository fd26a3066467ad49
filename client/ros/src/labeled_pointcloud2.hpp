#pragma once
// The labeled cloud as a ROS 1 message: the shared bridge's labeled_pointcloud2
// (ros_common/labeled_pointcloud2.hpp: the fields appended, the layout kept) with ROS 1's header.

#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include "primlabel/client/client.hpp"
#include "ros_common/labeled_pointcloud2.hpp"

namespace primlabel::rosnode {

using roscommon::LabeledFields;
using roscommon::probability_field_name;

// The header the labeled cloud carries: the frame_id and stamp the service echoed, or the
// input's when the service echoed neither (a server older than the echo); the input's seq.
std_msgs::Header echoed_header(const std_msgs::Header& input, const v1::LabelSummary& summary);

// roscommon::labeled_pointcloud2 on the message, with echoed_header.
sensor_msgs::PointCloud2 labeled_pointcloud2(const sensor_msgs::PointCloud2& input,
                                             const client::LabelResult& result,
                                             const LabeledFields& fields);

}  // namespace primlabel::rosnode
