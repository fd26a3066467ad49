#pragma once
// The node's command line as a ROS 2 user (or `ros2 launch`) writes it for any node:
//   primlabel-ros2 --ros-args -p server:=labeler:50051 -p model:=tabletop-kinect
//       -r __ns:=/robot -r points:=/camera/depth/points -p domain_id:=7
//       --params-file params.yaml --log-level debug
// `-p name:=value` sets a parameter (the ROS 1 node's, ros_common/node_parameters.hpp, plus
// domain_id, use_sim_time and ROS 2's qos_overrides.<topic>.<publisher|subscription>.<policy>),
// `--params-file FILE` sets those a ROS 2 parameters file gives this node
// (ros2_params_file.hpp), later arguments overriding earlier ones; `-r __ns:=/ns` and
// `-r __node:=name` set the namespace and node name, `-r from:=to` remaps a topic;
// `--log-level LEVEL` (or `name:=LEVEL` for this node's logger) sets the log level.
// `--ros-args` itself may be left out; `--` ends it.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "primlabel/ros2/node_log.hpp"
#include "primlabel/ros2/ros2_qos.hpp"
#include "primlabel/ros_common/node_parameters.hpp"

namespace primlabel::ros2node {

struct Ros2Settings {
  roscommon::NodeParameters parameters;
  std::uint32_t domain_id = 0;  // -p domain_id, else $ROS_DOMAIN_ID, else 0
  std::string node_namespace = "/";
  std::string node_name = "primlabel_ros2";
  std::map<std::string, std::string> remaps;  // topic name as given -> as remapped
  Severity log_level = Severity::kInfo;
  // Accepted as ROS 2 nodes accept it; the node stamps nothing with its own clock (the outputs
  // carry their input's stamp), so simulated time changes nothing.
  bool use_sim_time = false;
  QosOverrides input_qos, output_qos, summary_qos;
  // Cyclone DDS's configuration as rmw_cyclonedds makes it from the discovery variables and
  // CYCLONEDDS_URI (ros2_discovery.hpp); empty = Cyclone DDS's defaults.
  std::string dds_config;
  // $ROS_DISTRO humble or older: Humble's ros_discovery_info (24-byte GIDs) and no type hashes;
  // else (Iron, Jazzy, later, or unset) 16-byte GIDs and type hashes.
  bool humble_graph = false;
};

// Parses `arguments` (argv without the program). Throws std::invalid_argument naming the
// argument: an unknown parameter, a value of the wrong type (a boolean is true/false, a
// viewpoint [x, y, z]), a domain id outside 0..232, an invalid namespace or node name, a
// parameters file it cannot read, a QoS override for a topic the node does not have or a
// policy it does not take, an unknown log level, bad discovery variables, and what
// roscommon::check_parameters refuses.
Ros2Settings parse_arguments(const std::vector<std::string>& arguments);

// The fully qualified ROS 2 name of one of the node's topic parameters: remapped, resolved in
// the namespace.
std::string ros_topic(const Ros2Settings& settings, const std::string& topic);

// The DDS topic for one of the node's topic parameters: ros_topic prefixed "rt" (ros2_names.hpp).
std::string dds_topic(const Ros2Settings& settings, const std::string& topic);

}  // namespace primlabel::ros2node
