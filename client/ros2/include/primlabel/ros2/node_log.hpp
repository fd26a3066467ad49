#pragma once
// The node's log lines on stderr, as a ROS 2 node's console output reads:
// `[INFO] [1700000000.123456789] [primlabel_ros2]: ...`.

#include <optional>
#include <string>

namespace primlabel::ros2node {

enum class Severity { kDebug, kInfo, kWarn, kError, kFatal };

// ROS 2's --log-level names, in any case: debug, info, warn, error, fatal.
std::optional<Severity> severity_named(const std::string& name);

// Lines below `severity` are dropped (--log-level; INFO by default). FATAL lines always show.
void set_log_level(Severity severity);

void log(Severity severity, const std::string& node, const std::string& text);

}  // namespace primlabel::ros2node
