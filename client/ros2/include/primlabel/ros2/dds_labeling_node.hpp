#pragma once
// The ROS 2 node over Cyclone DDS: each sensor_msgs/msg/PointCloud2 on the input topic is labeled
// through the service (ros_common/cloud_labeler.hpp) and published with a `label` field, its
// summary beside it as std_msgs/msg/String JSON (README: client/ros2/README.md).
//
// The input reader keeps one cloud and a newer one replaces it, so a slow server makes the node
// skip scans, never fall behind. A failed cloud (a layout it cannot read, an error status from
// the service, a server that is down) is logged and the node goes on with the next one.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "primlabel/ros2/dds_entity.hpp"
#include "primlabel/ros2/ros2_arguments.hpp"
#include "primlabel/ros2/ros_discovery_info.hpp"
#include "primlabel/ros_common/cloud_labeler.hpp"

namespace primlabel::ros2node {

class DdsLabelingNode {
 public:
  // Joins the settings' DDS domain (configured as rmw_cyclonedds configures it), creates the
  // topics, the reader and the writers, and announces the node on ros_discovery_info. Throws
  // std::runtime_error when DDS refuses (e.g. a bad CYCLONEDDS_URI).
  explicit DdsLabelingNode(const Ros2Settings& settings);
  // Withdraws the node from ros_discovery_info.
  ~DdsLabelingNode();
  DdsLabelingNode(const DdsLabelingNode&) = delete;
  DdsLabelingNode& operator=(const DdsLabelingNode&) = delete;

  // Labels clouds as they come until `stop` is set (checked at least every `poll`).
  void run(const std::atomic<bool>& stop, std::chrono::milliseconds poll);

  std::uint64_t labeled() const { return labeled_; }
  std::uint64_t failed() const { return failed_; }

 private:
  void take_and_label();
  void label(const roscommon::PointCloud2View& cloud);

  Ros2Settings settings_;
  roscommon::CloudLabeler labeler_;
  // The domain (when the node configures it) owns the participant, the participant the rest;
  // members are destroyed in reverse, the domain last.
  DdsEntity domain_;
  DdsEntity participant_;
  DdsEntity reader_, cloud_writer_, summary_writer_;
  DdsEntity waitset_, data_available_;
  std::unique_ptr<RosDiscoveryInfo> discovery_info_;
  std::uint64_t labeled_ = 0, failed_ = 0;
  std::chrono::steady_clock::time_point last_domain_warning_{};
  bool warned_domain_ = false;
};

}  // namespace primlabel::ros2node
