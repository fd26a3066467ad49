#pragma once
// A ROS 2 parameters file (`--params-file FILE`, what `ros2 launch` passes), read as rcl reads
// one: node names as keys (`/**`, `/*`, `name`, `/ns/name`, or nested `ns: name:`), then
// `ros__parameters:`, then the parameters; nested maps are flattened with '.', so
//   /**:
//     ros__parameters:
//       qos_overrides:
//         /points:
//           subscription:
//             reliability: reliable
// names `qos_overrides./points.subscription.reliability`.
//
// The YAML is the subset ROS 2's files use (launch_ros writes it with PyYAML): block maps and
// sequences, flow sequences [a, b], plain, 'single' and "double" quoted scalars, comments.
// Anything else (flow maps, anchors and aliases, tags, multi-line scalars, tabs for indentation)
// is refused with the file's line, never guessed.

#include <string>
#include <utility>
#include <vector>

namespace primlabel::ros2node {

struct FileParameter {
  std::string name;
  std::string value;  // as a -p value: a scalar's text, a sequence as "[a, b, c]"
};

// The parameters in `path` for the node whose fully qualified name is `node_fqn` ("/ns/name"),
// in the file's order (a later entry overrides an earlier one). Throws std::invalid_argument
// naming the file and line: unreadable, larger than 1 MiB, not the subset above, a node entry
// without ros__parameters, a parameter without a value.
std::vector<FileParameter> read_params_file(const std::string& path, const std::string& node_fqn);

// Whether a node key of a parameters file (wildcards `/**`: any tokens, `/*`: one token; a key
// without a leading '/' gets one) names the node `node_fqn`.
bool node_key_matches(const std::string& key, const std::string& node_fqn);

}  // namespace primlabel::ros2node
