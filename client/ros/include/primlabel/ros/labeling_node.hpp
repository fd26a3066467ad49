#pragma once
// The node: each PointCloud2 on the input topic is labeled through the service and published
// with a `label` field (README: client/ros/README.md), its summary beside it as JSON.
//
// The subscription queue holds one cloud and drops the older one when a newer arrives, so a
// slow server makes the node skip scans, never fall behind. A failed cloud (a layout it cannot
// read, an error status from the service) is logged with ROS_ERROR and the node goes on.

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstdint>

#include "primlabel/ros_common/cloud_labeler.hpp"
#include "primlabel/ros_common/node_parameters.hpp"

namespace primlabel::rosnode {

class LabelingNode {
 public:
  // Subscribes and advertises on `node` (topic names resolve in its namespace).
  LabelingNode(ros::NodeHandle& node, const roscommon::NodeParameters& parameters);

  void on_cloud(const sensor_msgs::PointCloud2ConstPtr& cloud);

  std::uint64_t labeled() const { return labeled_; }
  std::uint64_t failed() const { return failed_; }

 private:
  roscommon::NodeParameters parameters_;
  roscommon::CloudLabeler labeler_;
  ros::Publisher cloud_publisher_;
  ros::Publisher summary_publisher_;
  ros::Subscriber subscriber_;
  std::uint64_t labeled_ = 0, failed_ = 0;
};

}  // namespace primlabel::rosnode
