#include "primlabel/ros2/ros2_arguments.hpp"

#include <array>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "primlabel/ros2/ros2_discovery.hpp"
#include "primlabel/ros2/ros2_names.hpp"
#include "primlabel/ros2/ros2_params_file.hpp"

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

// What is left to apply once every argument is read: QoS overrides name topics, which the
// remaps and the namespace resolve.
struct QosParameter {
  std::string value;
  std::string origin;  // "--params-file FILE: " or empty, for the error message
};
using QosParameters = std::map<std::string, QosParameter>;

void set_parameter(Ros2Settings& s, QosParameters& qos, const std::string& name,
                   const std::string& raw, const std::string& origin = "") {
  roscommon::NodeParameters& p = s.parameters;
  const std::string text = unquoted(raw);
  if (name.rfind("qos_overrides.", 0) == 0) {
    qos[name] = {text, origin};
    return;
  }
  std::string* const strings[] = {&p.server,          &p.token,        &p.token_file,
                                  &p.tls_ca,          &p.tls_cert,     &p.tls_key,
                                  &p.tls_server_name, &p.model,        &p.model_version,
                                  &p.input_topic,     &p.output_topic, &p.summary_topic,
                                  &p.units};
  const char* const string_names[] = {
      "server",          "token", "token_file",    "tls_ca",      "tls_cert",     "tls_key",
      "tls_server_name", "model", "model_version", "input_topic", "output_topic", "summary_topic",
      "units"};
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
  } else if (name == "use_sim_time") {
    s.use_sim_time = to_bool(name, text);
  } else {
    throw std::invalid_argument("unknown parameter '" + name +
                                "' (primlabel-ros2 --help lists them)");
  }
}

// One `qos_overrides.<topic>.<publisher|subscription>.<policy>` parameter applied to `o`.
void apply_qos_policy(QosOverrides& o, bool subscription, const std::string& name,
                      const std::string& policy, const std::string& value) {
  const auto bad = [&](const std::string& expected) {
    return std::invalid_argument("parameter " + name + " must be " + expected + ", not '" + value +
                                 "'");
  };
  if (policy == "reliability") {
    if (value == "reliable")
      o.reliability = DDS_RELIABILITY_RELIABLE;
    else if (value == "best_effort")
      o.reliability = DDS_RELIABILITY_BEST_EFFORT;
    // DDS's own default, which rmw_cyclonedds leaves in place: best effort read, reliable written.
    else if (value == "system_default")
      o.reliability = subscription ? DDS_RELIABILITY_BEST_EFFORT : DDS_RELIABILITY_RELIABLE;
    else
      throw bad("reliable, best_effort or system_default");
  } else if (policy == "history") {
    if (value == "keep_last" || value == "system_default")
      o.history = DDS_HISTORY_KEEP_LAST;
    else if (value == "keep_all")
      o.history = DDS_HISTORY_KEEP_ALL;
    else
      throw bad("keep_last, keep_all or system_default");
  } else if (policy == "depth") {
    const long long depth = to_integer(name, value);
    if (depth < 1 || depth > kMaxQueuedSamples)
      throw bad("1.." + std::to_string(kMaxQueuedSamples) + " (samples kept)");
    o.depth = static_cast<int>(depth);
  } else if (policy == "durability") {
    if (value == "volatile" || value == "system_default")
      o.durability = DDS_DURABILITY_VOLATILE;
    else if (value == "transient_local")
      o.durability = DDS_DURABILITY_TRANSIENT_LOCAL;
    else
      throw bad("volatile, transient_local or system_default");
  } else {
    throw std::invalid_argument("parameter " + name + ": the node takes the QoS overrides " +
                                "reliability, history, depth and durability, not '" + policy + "'");
  }
}

// One QoS override parameter applied to the endpoint it names (its topic fully qualified).
void apply_qos_override(Ros2Settings& s, const std::string& name, const std::string& value,
                        const std::string& input, const std::string& output,
                        const std::string& summary) {
  const std::string rest = name.substr(std::string("qos_overrides.").size());
  const auto policy_at = rest.rfind('.');
  const auto kind_at = policy_at == std::string::npos || policy_at == 0
                           ? std::string::npos
                           : rest.rfind('.', policy_at - 1);
  if (kind_at == std::string::npos || kind_at == 0)
    throw std::invalid_argument("parameter " + name +
                                ": expected qos_overrides.<topic>.<publisher|subscription>."
                                "<policy>");
  const std::string topic = rest.substr(0, kind_at);
  const std::string kind = rest.substr(kind_at + 1, policy_at - kind_at - 1);
  const std::string policy = rest.substr(policy_at + 1);
  bool applied = false;
  if (kind == "subscription" && topic == input) {
    apply_qos_policy(s.input_qos, true, name, policy, value);
    applied = true;
  }
  if (kind == "publisher" && topic == output) {
    apply_qos_policy(s.output_qos, false, name, policy, value);
    applied = true;
  }
  if (kind == "publisher" && topic == summary) {
    apply_qos_policy(s.summary_qos, false, name, policy, value);
    applied = true;
  }
  if (!applied)
    throw std::invalid_argument("parameter " + name + ": the node subscribes to " + input +
                                " and publishes " + output + " and " + summary +
                                " (a QoS override names one of them, fully qualified, with "
                                "subscription or publisher)");
}

// The QoS override parameters, applied to the endpoints whose topics they name.
void apply_qos_overrides(Ros2Settings& s, const QosParameters& qos) {
  const std::string input = ros_topic(s, s.parameters.input_topic);
  const std::string output = ros_topic(s, s.parameters.output_topic);
  const std::string summary = ros_topic(s, s.parameters.summary_topic);
  for (const auto& [name, parameter] : qos) try {
      apply_qos_override(s, name, parameter.value, input, output, summary);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(parameter.origin + e.what());
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
  QosParameters qos;
  if (const char* env = std::getenv("ROS_DOMAIN_ID"); env && *env)
    set_parameter(s, qos, "domain_id", env);
  // Parameters and parameters files in their order (a later one wins), applied once the node's
  // name is known: a file's entries are chosen by it.
  struct Source {
    bool file;
    std::string name, value;  // a file: its path in `name`
  };
  std::vector<Source> sources;
  std::string log_level;
  for (std::size_t i = 0; i < arguments.size(); ++i) {
    const std::string& a = arguments[i];
    if (a == "--ros-args") continue;
    if (a == "--") break;
    const bool takes_value = a == "-p" || a == "--param" || a == "-r" || a == "--remap" ||
                             a == "--params-file" || a == "--log-level";
    if (!takes_value)
      throw std::invalid_argument("unknown argument '" + a +
                                  "' (ROS 2 style: --ros-args -p name:=value -r __ns:=/ns "
                                  "--params-file FILE --log-level LEVEL)");
    if (i + 1 == arguments.size())
      throw std::invalid_argument(a + (a == "--params-file" ? " needs a file"
                                       : a == "--log-level" ? " needs a level"
                                                            : " needs name:=value"));
    const std::string& value = arguments[++i];
    if (a == "--params-file") {
      sources.push_back({true, value, ""});
    } else if (a == "--log-level") {
      log_level = value;
    } else {
      const auto [name, assigned] = assignment(a, value);
      if (a == "-p" || a == "--param") {
        sources.push_back({false, name, assigned});
      } else if (name == "__ns") {
        s.node_namespace = assigned;
      } else if (name == "__node" || name == "__name") {
        s.node_name = assigned;
      } else {
        s.remaps[name] = assigned;
      }
    }
  }
  check_namespace(s.node_namespace);
  if (s.node_name.empty() || s.node_name.find('/') != std::string::npos)
    throw std::invalid_argument("node name '" + s.node_name + "' must be one token");
  // ros_discovery_info holds each in at most 256 characters.
  if (s.node_name.size() > 256 || s.node_namespace.size() > 256)
    throw std::invalid_argument("node name or namespace longer than 256 characters");
  const std::string node_fqn =
      s.node_namespace == "/" ? "/" + s.node_name : s.node_namespace + "/" + s.node_name;
  for (const Source& source : sources) {
    if (!source.file) {
      set_parameter(s, qos, source.name, source.value);
      continue;
    }
    const std::string origin = "--params-file " + source.name + ": ";
    for (const FileParameter& p : read_params_file(source.name, node_fqn)) try {
        set_parameter(s, qos, p.name, p.value, origin);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(origin + e.what());
      }
  }
  if (!log_level.empty()) {
    // `LEVEL`, or `logger:=LEVEL` for one logger: this node's is its name in its namespace
    // with '.' for '/' ("robot.labeler"); other loggers' levels concern no line of this node.
    const auto at = log_level.find(":=");
    const std::string level = at == std::string::npos ? log_level : log_level.substr(at + 2);
    const auto severity = severity_named(level);
    if (!severity)
      throw std::invalid_argument("--log-level " + log_level +
                                  ": the level is debug, info, warn, error or fatal");
    std::string logger = node_fqn.substr(1);
    for (char& c : logger)
      if (c == '/') c = '.';
    if (at == std::string::npos || log_level.substr(0, at) == logger) s.log_level = *severity;
  }
  roscommon::check_parameters(s.parameters, "");
  // Every topic must resolve now, not when the node first publishes.
  for (const std::string* topic :
       {&s.parameters.input_topic, &s.parameters.output_topic, &s.parameters.summary_topic})
    dds_topic(s, *topic);
  apply_qos_overrides(s, qos);
  s.dds_config = cyclone_config(discovery_environment());
  if (const char* distro = std::getenv("ROS_DISTRO"))
    for (const char* old : {"dashing", "eloquent", "foxy", "galactic", "humble"})
      if (std::string(distro) == old) s.humble_graph = true;
  return s;
}

std::string ros_topic(const Ros2Settings& settings, const std::string& topic) {
  const auto remapped = settings.remaps.find(topic);
  const std::string& name = remapped == settings.remaps.end() ? topic : remapped->second;
  return resolve_topic(name, settings.node_namespace, settings.node_name);
}

std::string dds_topic(const Ros2Settings& settings, const std::string& topic) {
  return dds_topic_name(ros_topic(settings, topic));
}

}  // namespace primlabel::ros2node
