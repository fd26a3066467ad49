// primlabel-ros: the ROS 1 node (client/ros/README.md). Without rosrun:
//   primlabel-ros _server:=127.0.0.1:50051 _model:=tabletop-kinect

#include <ros/ros.h>

#include <cstdio>
#include <cstring>
#include <exception>

#include "primlabel/build_version.hpp"
#include "primlabel/ros/labeling_node.hpp"
#include "primlabel/ros/node_parameters.hpp"

namespace {

constexpr const char* kUsage =
    "usage: primlabel-ros [_param:=value ...] [topic:=remapped ...]\n"
    "Labels sensor_msgs/PointCloud2 clouds through primlabel-server: subscribes to ~input_topic\n"
    "(points), publishes ~output_topic (points_labeled, the input's fields plus uint32 label) and\n"
    "~summary_topic (points_labeled_summary, std_msgs/String JSON).\n"
    "Parameters: server model model_version token token_file tls tls_ca tls_cert tls_key\n"
    "tls_server_name deadline retries voxel_size units every_point viewpoint tabletop_only "
    "confidence\n"
    "probabilities objects primitives\n"
    "input_topic output_topic summary_topic (client/ros/README.md).\n";

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--version") == 0) {
      std::printf("%s\n", primlabel::version_line("primlabel-ros").c_str());
      return 0;
    }
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::fputs(kUsage, stdout);
      return 0;
    }
  }
  ros::init(argc, argv, "primlabel_ros");
  ros::NodeHandle node;
  try {
    const primlabel::roscommon::NodeParameters parameters =
        primlabel::rosnode::read_parameters(ros::NodeHandle("~"));
    primlabel::rosnode::LabelingNode labeling(node, parameters);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("primlabel-ros: %s", e.what());
    return 2;
  }
  return 0;
}
