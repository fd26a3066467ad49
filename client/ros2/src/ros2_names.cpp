#include "primlabel/ros2/ros2_names.hpp"

#include <cctype>
#include <stdexcept>

namespace primlabel::ros2node {

namespace {

// "/a/b": tokens of [A-Za-z0-9_], none empty or starting with a digit (rcl's rules for a fully
// qualified name, without the substitutions).
bool valid_qualified(const std::string& name) {
  if (name.empty() || name[0] != '/') return false;
  if (name == "/") return true;
  if (name.back() == '/') return false;
  bool token_start = true;
  for (std::size_t i = 1; i < name.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    if (c == '/') {
      if (token_start) return false;  // "//"
      token_start = true;
      continue;
    }
    if (!std::isalnum(c) && c != '_') return false;
    if (token_start && std::isdigit(c)) return false;
    token_start = false;
  }
  return true;
}

std::string joined(const std::string& ns, const std::string& name) {
  return ns == "/" ? "/" + name : ns + "/" + name;
}

}  // namespace

void check_namespace(const std::string& ns) {
  if (!valid_qualified(ns))
    throw std::invalid_argument("namespace '" + ns +
                                "' is not a ROS 2 namespace (\"/\" or \"/a/b\", tokens of "
                                "[A-Za-z0-9_] not starting with a digit)");
}

std::string resolve_topic(const std::string& name, const std::string& ns, const std::string& node) {
  std::string resolved;
  if (name.rfind("~/", 0) == 0)
    resolved = joined(joined(ns, node), name.substr(2));
  else if (!name.empty() && name[0] == '/')
    resolved = name;
  else
    resolved = joined(ns, name);
  if (resolved == "/" || !valid_qualified(resolved))
    throw std::invalid_argument("topic '" + name + "' is not a ROS 2 topic name (resolved: '" +
                                resolved + "')");
  return resolved;
}

std::string dds_topic_name(const std::string& resolved) { return "rt" + resolved; }

}  // namespace primlabel::ros2node
