#include "primlabel/ros/labeling_node.hpp"

#include <std_msgs/String.h>

#include <exception>

#include "primlabel/ros/pointcloud2_message.hpp"

namespace primlabel::rosnode {

LabelingNode::LabelingNode(ros::NodeHandle& node, const roscommon::NodeParameters& parameters)
    : parameters_(parameters), labeler_(parameters) {
  cloud_publisher_ = node.advertise<sensor_msgs::PointCloud2>(parameters.output_topic, 1);
  summary_publisher_ = node.advertise<std_msgs::String>(parameters.summary_topic, 1);
  // Queue size 1: roscpp drops the oldest queued cloud when a newer one arrives.
  subscriber_ = node.subscribe(parameters.input_topic, 1, &LabelingNode::on_cloud, this,
                               ros::TransportHints().tcpNoDelay());
  ROS_INFO("primlabel-ros: labeling %s -> %s (summary %s) through %s: %s",
           subscriber_.getTopic().c_str(), cloud_publisher_.getTopic().c_str(),
           summary_publisher_.getTopic().c_str(), parameters.server.c_str(),
           roscommon::settings_text(parameters).c_str());
}

void LabelingNode::on_cloud(const sensor_msgs::PointCloud2ConstPtr& cloud) {
  const std::string& frame = cloud->header.frame_id;
  try {
    roscommon::LabeledCloud labeled = labeler_.label(view_of(*cloud));
    if (!labeled.domain_warning.empty())
      ROS_WARN_THROTTLE(60, "primlabel-ros: %s", labeled.domain_warning.c_str());
    if (labeled.model_change) ROS_INFO("primlabel-ros: %s", labeled.model_change->c_str());
    // The echoed frame and stamp, the input's seq.
    std_msgs::Header header = cloud->header;
    header.frame_id = labeled.cloud.frame_id;
    header.stamp.fromNSec(labeled.cloud.stamp_ns);
    cloud_publisher_.publish(to_message(std::move(labeled.cloud), header));
    std_msgs::String summary;
    summary.data = labeled.summary_json;
    summary_publisher_.publish(summary);
    ++labeled_;
    ROS_DEBUG("primlabel-ros: labeled %zu points of frame %s, request %s", labeled.points,
              frame.c_str(), labeled.request_id.c_str());
  } catch (const std::exception& e) {  // a ClientError's text starts with the status code
    ++failed_;
    ROS_ERROR("primlabel-ros: cloud of frame '%s' (stamp %.9f) not labeled: %s", frame.c_str(),
              cloud->header.stamp.toSec(), e.what());
  }
}

}  // namespace primlabel::rosnode
