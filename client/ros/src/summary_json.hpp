#pragma once
// The summary JSON the node publishes, from the shared bridge (ros_common/summary_json.hpp).

#include "ros_common/summary_json.hpp"

namespace primlabel::rosnode {

using roscommon::summary_json;

}  // namespace primlabel::rosnode
