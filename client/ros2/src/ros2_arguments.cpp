#include "ros2_arguments.hpp"

#include <array>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "ros2_names.hpp"

namespace primlabel::ros2node {

namespace {

// A value as ROS 2 parses a -p value (YAML): quotes around a string are dropped.
std::string unquoted(const std::string& text) {
  if (text.size() >= 2 && (text.front() == '\'' || text.front() == '"') &&
      text.back() == text.front())
    return text.substr(1, text.size() - 2);
  return text;
}

bool to_bool(const std::string& name, const std::string& text) {
  if (text == "true" || text == "True" || text == "TRUE") return true;
  if (text == "false" || text == "False" || text == "FALSE") return false;
  throw std::invalid_argument("parameter " + name + " must be a boolean (true or false), not '" +
                              text + "'");
}

double to_double(const std::string& name, const std::string& text) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size())
    throw std::invalid_argument("parameter " + name + " must be a number, not '" + text + "'");
  return value;
}

long long to_integer(const std::string& name, const std::string& text) {
  std::size_t used = 0;
  long long value = 0;
  try {
    value = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size())
    throw std::invalid_argument("parameter " + name + " must be an integer, not '" + text + "'");
  return value;
}

std::array<double, 3> to_point(const std::string& name, const std::string& text) {
  const auto bad = [&] {
    return std::invalid_argument("parameter " + name +
                                 " must be three finite numbers [x, y, z] (metres, in the "
                                 "cloud's frame), not '" +
                                 text + "'");
  };
  if (text.size() < 2 || text.front() != '[' || text.back() != ']') throw bad();
  std::stringstream items(text.substr(1, text.size() - 2));
  std::array<double, 3> xyz{};
  std::string item;
  int k = 0;
  while (std::getline(items, item, ',')) {
    if (k == 3) throw bad();
    const auto first = item.find_first_not_of(' ');
    const auto last = item.find_last_not_of(' ');
    if (first == std::string::npos) throw bad();
    try {
      xyz[k] = to_double(name, item.substr(first, last - first + 1));
    } catch (const std::invalid_argument&) {
      throw bad();
    }
    if (!std::isfinite(xyz[k++])) throw bad();
  }
  if (k != 3) throw bad();
  return xyz;
}

void set_parameter(Ros2Settings& s, const std::string& name, const std::string& raw) {
  roscommon::NodeParameters& p = s.parameters;
  const std::string text = unquoted(raw);
  std::string* const strings[] = {&p.server,          &p.token,        &p.token_file,
                                  &p.tls_ca,          &p.tls_cert,     &p.tls_key,
                                  &p.tls_server_name, &p.model,        &p.model_version,
                                  &p.input_topic,     &p.output_topic, &p.summary_topic};
  const char* const string_names[] = {
      "server",          "token", "token_file",    "tls_ca",      "tls_cert",     "tls_key",
      "tls_server_name", "model", "model_version", "input_topic", "output_topic", "summary_topic"};
  for (std::size_t k = 0; k < std::size(strings); ++k)
    if (name == string_names[k]) {
      *strings[k] = text;
      return;
    }
  bool* const flags[] = {&p.tls,        &p.every_point, &p.tabletop_only, &p.objects,
                         &p.primitives, &p.confidence,  &p.probabilities};
  const char* const flag_names[] = {"tls",        "every_point", "tabletop_only", "objects",
                                    "primitives", "confidence",  "probabilities"};
  for (std::size_t k = 0; k < std::size(flags); ++k)
    if (name == flag_names[k]) {
      *flags[k] = to_bool(name, text);
      return;
    }
  if (name == "deadline") {
    p.deadline = to_double(name, text);
  } else if (name == "voxel_size") {
    p.voxel_size = to_double(name, text);
  } else if (name == "retries") {
    const long long retries = to_integer(name, text);
    if (retries < 1 || retries > 1000)
      throw std::invalid_argument("parameter retries must be 1..1000 (attempts in all)");
    p.retries = static_cast<int>(retries);
  } else if (name == "viewpoint") {
    p.viewpoint = to_point(name, text);
  } else if (name == "domain_id") {
    const long long id = to_integer(name, text);
    // DDS's RTPS port mapping leaves room for domains 0..232.
    if (id < 0 || id > 232) throw std::invalid_argument("parameter domain_id must be 0..232");
    s.domain_id = static_cast<std::uint32_t>(id);
  } else {
    throw std::invalid_argument("unknown parameter '" + name +
                                "' (primlabel-ros2 --help lists them)");
  }
}

// "name:=value" split at ":=".
std::pair<std::string, std::string> assignment(const std::string& option, const std::string& text) {
  const auto at = text.find(":=");
  if (at == std::string::npos || at == 0)
    throw std::invalid_argument(option + " " + text + ": expected name:=value");
  return {text.substr(0, at), text.substr(at + 2)};
}

}  // namespace

Ros2Settings parse_arguments(const std::vector<std::string>& arguments) {
  Ros2Settings s;
  if (const char* env = std::getenv("ROS_DOMAIN_ID"); env && *env)
    set_parameter(s, "domain_id", env);
  for (std::size_t i = 0; i < arguments.size(); ++i) {
    const std::string& a = arguments[i];
    if (a == "--ros-args") continue;
    if (a == "--") break;
    if (a == "-p" || a == "--param" || a == "-r" || a == "--remap") {
      if (i + 1 == arguments.size()) throw std::invalid_argument(a + " needs name:=value");
      const auto [name, value] = assignment(a, arguments[++i]);
      if (a == "-p" || a == "--param") {
        set_parameter(s, name, value);
      } else if (name == "__ns") {
        s.node_namespace = value;
      } else if (name == "__node" || name == "__name") {
        s.node_name = value;
      } else {
        s.remaps[name] = value;
      }
      continue;
    }
    throw std::invalid_argument("unknown argument '" + a +
                                "' (ROS 2 style: --ros-args -p name:=value -r __ns:=/ns)");
  }
  check_namespace(s.node_namespace);
  if (s.node_name.empty() || s.node_name.find('/') != std::string::npos)
    throw std::invalid_argument("node name '" + s.node_name + "' must be one token");
  roscommon::check_parameters(s.parameters, "");
  // Every topic must resolve now, not when the node first publishes.
  for (const std::string* topic :
       {&s.parameters.input_topic, &s.parameters.output_topic, &s.parameters.summary_topic})
    dds_topic(s, *topic);
  return s;
}

std::string dds_topic(const Ros2Settings& settings, const std::string& topic) {
  const auto remapped = settings.remaps.find(topic);
  const std::string& name = remapped == settings.remaps.end() ? topic : remapped->second;
  return dds_topic_name(resolve_topic(name, settings.node_namespace, settings.node_name));
}

}  // namespace primlabel::ros2node
