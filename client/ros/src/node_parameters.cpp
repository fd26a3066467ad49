#include "primlabel/ros/node_parameters.hpp"

#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace primlabel::rosnode {

namespace {

template <class T>
constexpr const char* type_name() {
  if constexpr (std::is_same_v<T, std::string>) return "a string";
  if constexpr (std::is_same_v<T, bool>) return "a boolean";
  if constexpr (std::is_same_v<T, int>) return "an integer";
  return "a number";
}

// `value` from ~key when that is set; a value of another type is an error, not the default.
template <class T>
void read(const ros::NodeHandle& node, const std::string& key, T& value) {
  if (!node.hasParam(key)) return;
  if (!node.getParam(key, value))
    throw std::invalid_argument("~" + key + " must be " + type_name<T>());
}

}  // namespace

roscommon::NodeParameters read_parameters(const ros::NodeHandle& node) {
  roscommon::NodeParameters p;
  read(node, "server", p.server);
  read(node, "token", p.token);
  read(node, "token_file", p.token_file);
  read(node, "tls", p.tls);
  read(node, "tls_ca", p.tls_ca);
  read(node, "tls_cert", p.tls_cert);
  read(node, "tls_key", p.tls_key);
  read(node, "tls_server_name", p.tls_server_name);
  read(node, "deadline", p.deadline);
  read(node, "retries", p.retries);
  read(node, "model", p.model);
  read(node, "model_version", p.model_version);
  read(node, "voxel_size", p.voxel_size);
  read(node, "every_point", p.every_point);
  read(node, "units", p.units);
  if (node.hasParam("viewpoint")) {
    std::vector<double> xyz;
    if (!node.getParam("viewpoint", xyz) || xyz.size() != 3 || !std::isfinite(xyz[0]) ||
        !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
      throw std::invalid_argument(
          "~viewpoint must be a list of three finite numbers [x, y, z] (metres, in the cloud's "
          "frame)");
    p.viewpoint = std::array<double, 3>{xyz[0], xyz[1], xyz[2]};
  }
  read(node, "tabletop_only", p.tabletop_only);
  read(node, "objects", p.objects);
  read(node, "primitives", p.primitives);
  read(node, "confidence", p.confidence);
  read(node, "probabilities", p.probabilities);
  read(node, "input_topic", p.input_topic);
  read(node, "output_topic", p.output_topic);
  read(node, "summary_topic", p.summary_topic);

  roscommon::check_parameters(p, "~");
  return p;
}

}  // namespace primlabel::rosnode
