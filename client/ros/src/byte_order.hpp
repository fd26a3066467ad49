#pragma once
// needs_swap for the ROS 1 code and its tests, from the shared bridge (ros_common).

#include "ros_common/byte_order.hpp"

namespace primlabel::rosnode {

using roscommon::needs_swap;

}  // namespace primlabel::rosnode
