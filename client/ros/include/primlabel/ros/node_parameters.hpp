#pragma once
// The node's private parameters (~server, ~model, ...; README: client/ros/README.md), read from
// the parameter server. What they are and make is the shared bridge's
// (primlabel/ros_common/node_parameters.hpp).

#include <ros/node_handle.h>

#include "primlabel/ros_common/node_parameters.hpp"

namespace primlabel::rosnode {

// Reads the parameters under `private_node` (a NodeHandle on "~"), defaults where unset. Throws
// std::invalid_argument naming the parameter: a wrong type, a negative or non-finite voxel size,
// a viewpoint that is not three finite numbers,
// a deadline <= 0, retries < 1, an empty topic, a malformed server address, ~objects without
// ~tabletop_only.
roscommon::NodeParameters read_parameters(const ros::NodeHandle& private_node);

}  // namespace primlabel::rosnode
