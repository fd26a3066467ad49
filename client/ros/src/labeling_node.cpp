#include "labeling_node.hpp"

#include <std_msgs/String.h>

#include <exception>

#include "pointcloud2_xyz.hpp"
#include "summary_json.hpp"

namespace primlabel::rosnode {

LabelingNode::LabelingNode(ros::NodeHandle& node, const NodeParameters& parameters)
    : parameters_(parameters),
      client_(client_options(parameters)),
      label_options_(label_options(parameters)),
      fields_{parameters.confidence, parameters.probabilities, parameters.objects,
              parameters.primitives} {
  cloud_publisher_ = node.advertise<sensor_msgs::PointCloud2>(parameters.output_topic, 1);
  summary_publisher_ = node.advertise<std_msgs::String>(parameters.summary_topic, 1);
  // Queue size 1: roscpp drops the oldest queued cloud when a newer one arrives.
  subscriber_ = node.subscribe(parameters.input_topic, 1, &LabelingNode::on_cloud, this,
                               ros::TransportHints().tcpNoDelay());
  ROS_INFO("primlabel-ros: labeling %s -> %s (summary %s) through %s: %s",
           subscriber_.getTopic().c_str(), cloud_publisher_.getTopic().c_str(),
           summary_publisher_.getTopic().c_str(), parameters.server.c_str(),
           settings_text(parameters).c_str());
}

void LabelingNode::on_cloud(const sensor_msgs::PointCloud2ConstPtr& cloud) {
  const std::string& frame = cloud->header.frame_id;
  try {
    const PointCloud points = xyz_from_pointcloud2(*cloud);
    client::LabelOptions options = label_options_;
    options.frame_id = frame;
    options.stamp_ns = cloud->header.stamp.toNSec();
    options.scan_id = frame + "@" + std::to_string(options.stamp_ns);
    const client::LabelResult result = client_.label(points, options);
    if (!result.summary.domain_warning().empty())
      ROS_WARN_THROTTLE(60, "primlabel-ros: %s", result.summary.domain_warning().c_str());
    // Which model labels the clouds, and why, each time it changes (not every frame).
    const std::string model = result.summary.model() + " " + result.summary.model_version();
    if (model != last_model_) {
      last_model_ = model;
      ROS_INFO("primlabel-ros: model %s labels frame '%s' (%s)", model.c_str(), frame.c_str(),
               client::model_choice_text(result.summary).c_str());
    }
    cloud_publisher_.publish(labeled_pointcloud2(*cloud, result, fields_));
    std_msgs::String summary;
    summary.data = summary_json(result.summary);
    summary_publisher_.publish(summary);
    ++labeled_;
    ROS_DEBUG("primlabel-ros: labeled %zu points of frame %s, request %s", result.size(),
              frame.c_str(), result.summary.request_id().c_str());
  } catch (const std::exception& e) {  // a ClientError's text starts with the status code
    ++failed_;
    ROS_ERROR("primlabel-ros: cloud of frame '%s' (stamp %.9f) not labeled: %s", frame.c_str(),
              cloud->header.stamp.toSec(), e.what());
  }
}

}  // namespace primlabel::rosnode
