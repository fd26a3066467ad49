#pragma once
// ROS 2's names as rmw_cyclonedds puts them on DDS: a topic `/ns/name` is the DDS topic
// `rt/ns/name` (rmw's "ROS topic" prefix); relative names resolve in the node's namespace, `~/x`
// under the node's own name.

#include <string>

namespace primlabel::ros2node {

// Throws std::invalid_argument unless `ns` is a ROS 2 namespace: "/" or "/a/b" of
// [A-Za-z0-9_] tokens, none starting with a digit.
void check_namespace(const std::string& ns);

// The fully qualified name of topic `name` for node `node` in namespace `ns` ("points" in
// "/robot" is "/robot/points"; "/points" stays; "~/out" is "/robot/<node>/out"). Throws
// std::invalid_argument naming the topic when it is not a valid ROS 2 topic name.
std::string resolve_topic(const std::string& name, const std::string& ns, const std::string& node);

// The DDS topic of a fully qualified ROS 2 topic: "rt" + name.
std::string dds_topic_name(const std::string& resolved);

}  // namespace primlabel::ros2node
