#pragma once
// The node's private parameters (~server, ~model, ...; README: client/ros/README.md), read from
// the parameter server.

#include <ros/node_handle.h>

#include "ros_common/node_parameters.hpp"

namespace primlabel::rosnode {

// The parameters and what they make are the shared bridge's (ros_common/node_parameters.hpp).
using roscommon::client_options;
using roscommon::label_options;
using roscommon::NodeParameters;
using roscommon::settings_text;

// Reads the parameters under `private_node` (a NodeHandle on "~"), defaults where unset. Throws
// std::invalid_argument naming the parameter: a wrong type, a negative or non-finite voxel size,
// a viewpoint that is not three finite numbers,
// a deadline <= 0, retries < 1, an empty topic, a malformed server address, ~objects without
// ~tabletop_only.
NodeParameters read_parameters(const ros::NodeHandle& private_node);

}  // namespace primlabel::rosnode
