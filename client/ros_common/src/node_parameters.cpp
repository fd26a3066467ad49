#include "primlabel/ros_common/node_parameters.hpp"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/server_address.hpp"

namespace primlabel::roscommon {

namespace {

std::string trimmed(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
}

}  // namespace

void check_parameters(NodeParameters& p, const std::string& prefix) {
  try {
    p.server = client::tools::server_address_with_port(p.server);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(prefix + "server: " + std::string(e.what()));
  }
  if (!std::isfinite(p.voxel_size) || p.voxel_size < 0)
    throw std::invalid_argument(prefix + "voxel_size must be a finite number >= 0 (metres)");
  if (p.units != "m" && p.units != "cm" && p.units != "mm")
    throw std::invalid_argument(prefix + "units must be m, cm or mm, got '" + p.units + "'");
  if (!std::isfinite(p.deadline) || p.deadline <= 0)
    throw std::invalid_argument(prefix + "deadline must be a finite number of seconds > 0");
  if (p.objects && !p.tabletop_only)
    throw std::invalid_argument(prefix + "objects needs " + prefix +
                                "tabletop_only:=true (the objects are the table-top stage's)");
  if (p.retries < 1) throw std::invalid_argument(prefix + "retries must be >= 1 (attempts in all)");
  if (p.input_topic.empty() || p.output_topic.empty() || p.summary_topic.empty())
    throw std::invalid_argument(prefix + "input_topic, " + prefix + "output_topic and " + prefix +
                                "summary_topic must not be empty");
}

client::ClientOptions client_options(const NodeParameters& p) {
  client::ClientOptions options;
  options.address = p.server;
  options.deadline = std::chrono::milliseconds(static_cast<long long>(p.deadline * 1000));
  options.retry_attempts = p.retries;
  if (p.tls || !p.tls_ca.empty() || !p.tls_cert.empty() || !p.tls_key.empty())
    options.tls = client::TlsOptions{p.tls_ca, p.tls_cert, p.tls_key, p.tls_server_name};
  if (!p.token.empty()) {
    options.bearer_token = trimmed(p.token);
  } else if (!p.token_file.empty()) {
    std::ifstream in(p.token_file);
    std::stringstream text;
    text << in.rdbuf();
    if (!in) throw std::runtime_error("token_file " + p.token_file + ": cannot read it");
    options.bearer_token = trimmed(text.str());
  } else if (const char* env = std::getenv("PRIMLABEL_TOKEN")) {
    options.bearer_token = trimmed(env);
  }
  return options;
}

client::LabelOptions label_options(const NodeParameters& p) {
  client::LabelOptions options;
  options.model = p.model;
  options.model_version = p.model_version;
  options.voxel_size = static_cast<float>(p.voxel_size);
  options.every_point = p.every_point;
  options.metres_per_unit = p.units == "mm" ? 0.001f : p.units == "cm" ? 0.01f : 1.0f;
  if (p.viewpoint)
    options.viewpoint =
        Vec3f(static_cast<float>((*p.viewpoint)[0]), static_cast<float>((*p.viewpoint)[1]),
              static_cast<float>((*p.viewpoint)[2]));
  options.tabletop_only = p.tabletop_only;
  options.objects = p.objects;
  options.primitives = p.primitives;
  options.probabilities = p.confidence || p.probabilities;
  return options;
}

std::string settings_text(const NodeParameters& p) {
  const auto flag = [](bool value) { return value ? "true" : "false"; };
  std::ostringstream out;
  out << "model " << (p.model.empty() ? "(the one whose domain fits each cloud)" : p.model);
  if (!p.model_version.empty()) out << " version " << p.model_version;
  out << ", tabletop_only " << flag(p.tabletop_only) << ", every_point " << flag(p.every_point)
      << ", voxel_size ";
  if (p.voxel_size > 0.0)
    out << p.voxel_size << " m";
  else
    out << "the model's";
  out << ", units " << p.units << ", viewpoint ";
  if (p.viewpoint)
    out << (*p.viewpoint)[0] << "," << (*p.viewpoint)[1] << "," << (*p.viewpoint)[2];
  else
    out << "the frame's origin";
  out << ", objects " << flag(p.objects) << ", primitives " << flag(p.primitives) << ", confidence "
      << flag(p.confidence) << ", probabilities " << flag(p.probabilities);
  return out.str();
}

}  // namespace primlabel::roscommon
