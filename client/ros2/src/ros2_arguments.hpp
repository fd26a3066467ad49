#pragma once
// The node's command line as a ROS 2 user writes it for any node:
//   primlabel-ros2 --ros-args -p server:=labeler:50051 -p model:=tabletop-kinect
//       -r __ns:=/robot -r points:=/camera/depth/points -p domain_id:=7
// `-p name:=value` sets a parameter (the ROS 1 node's, ros_common/node_parameters.hpp, plus
// domain_id), `-r __ns:=/ns` and `-r __node:=name` set the namespace and node name, `-r from:=to`
// remaps a topic. `--ros-args` itself may be left out; `--` ends it.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "ros_common/node_parameters.hpp"

namespace primlabel::ros2node {

struct Ros2Settings {
  roscommon::NodeParameters parameters;
  std::uint32_t domain_id = 0;  // -p domain_id, else $ROS_DOMAIN_ID, else 0
  std::string node_namespace = "/";
  std::string node_name = "primlabel_ros2";
  std::map<std::string, std::string> remaps;  // topic name as given -> as remapped
};

// Parses `arguments` (argv without the program). Throws std::invalid_argument naming the
// argument: an unknown parameter, a value of the wrong type (a boolean is true/false, a
// viewpoint [x, y, z]), a domain id outside 0..232, an invalid namespace or node name, and what
// roscommon::check_parameters refuses.
Ros2Settings parse_arguments(const std::vector<std::string>& arguments);

// The DDS topic for one of the node's topic parameters: remapped, resolved in the namespace,
// prefixed "rt" (ros2_names.hpp).
std::string dds_topic(const Ros2Settings& settings, const std::string& topic);

}  // namespace primlabel::ros2node
