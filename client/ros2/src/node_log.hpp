#pragma once
// The node's log lines on stderr, as a ROS 2 node's console output reads:
// `[INFO] [1700000000.123456789] [primlabel_ros2]: ...`.

#include <string>

namespace primlabel::ros2node {

enum class Severity { kInfo, kWarn, kError, kFatal };

void log(Severity severity, const std::string& node, const std::string& text);

}  // namespace primlabel::ros2node
