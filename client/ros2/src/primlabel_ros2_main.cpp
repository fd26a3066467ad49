// primlabel-ros2: the ROS 2 node over Cyclone DDS (client/ros2/README.md), e.g.
//   primlabel-ros2 --ros-args -p server:=127.0.0.1:50051 -p model:=tabletop-kinect

#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "primlabel/build_version.hpp"
#include "primlabel/ros2/dds_labeling_node.hpp"
#include "primlabel/ros2/node_log.hpp"

namespace {

constexpr const char* kUsage =
    "usage: primlabel-ros2 [--ros-args] [-p name:=value ...] [--params-file FILE ...]\n"
    "                      [-r __ns:=/ns] [-r __node:=name] [-r topic:=remapped ...]\n"
    "                      [--log-level debug|info|warn|error|fatal]\n"
    "Labels sensor_msgs/msg/PointCloud2 clouds through primlabel-server, speaking ROS 2's wire\n"
    "types over Cyclone DDS (no rclcpp): subscribes to input_topic (points), publishes\n"
    "output_topic (points_labeled, the input's fields plus uint32 label) and summary_topic\n"
    "(points_labeled_summary, std_msgs/msg/String JSON).\n"
    "Parameters: server model model_version token token_file tls tls_ca tls_cert tls_key\n"
    "tls_server_name deadline retries voxel_size units every_point viewpoint tabletop_only "
    "confidence\n"
    "probabilities objects primitives input_topic output_topic summary_topic domain_id\n"
    "(default $ROS_DOMAIN_ID, else 0) use_sim_time, and ROS 2's QoS overrides\n"
    "qos_overrides./<topic>.subscription|publisher.reliability|history|depth|durability\n"
    "(e.g. reliable input: -p qos_overrides./points.subscription.reliability:=reliable).\n"
    "Discovery follows ROS_LOCALHOST_ONLY, ROS_AUTOMATIC_DISCOVERY_RANGE, ROS_STATIC_PEERS and\n"
    "CYCLONEDDS_URI as rmw_cyclonedds does (client/ros2/README.md).\n";

std::atomic<bool> stop_requested{false};

void request_stop(int) { stop_requested.store(true); }

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--version") == 0) {
      std::printf("%s\n", primlabel::version_line("primlabel-ros2").c_str());
      return 0;
    }
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::fputs(kUsage, stdout);
      return 0;
    }
  }
  using namespace primlabel::ros2node;
  std::string node = "primlabel_ros2";
  try {
    const Ros2Settings settings = parse_arguments(std::vector<std::string>(argv + 1, argv + argc));
    node = settings.node_name;
    set_log_level(settings.log_level);
    DdsLabelingNode labeling(settings);
    std::signal(SIGINT, request_stop);
    std::signal(SIGTERM, request_stop);
    labeling.run(stop_requested, std::chrono::milliseconds(200));
    log(Severity::kInfo, node,
        "stopping after " + std::to_string(labeling.labeled()) + " clouds labeled, " +
            std::to_string(labeling.failed()) + " not");
  } catch (const std::exception& e) {
    log(Severity::kFatal, node, e.what());
    return 2;
  }
  return 0;
}
