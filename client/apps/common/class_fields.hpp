#pragma once
// The names of per-class output fields, one spelling in every format (PCD, PLY, the ROS node's
// PointCloud2): `prob_<class>` with the class name's characters outside [A-Za-z0-9_] as '_'
// ("prob_cylinder_convex"), or `prob_<id>` for a class without a name. C++17: the ROS node
// includes it.

#include <cctype>
#include <cstdint>
#include <string>

namespace primlabel::client::tools {

inline std::string probability_field_name(const std::string& class_name, std::uint32_t class_id) {
  if (class_name.empty()) return "prob_" + std::to_string(class_id);
  std::string name = "prob_" + class_name;
  for (char& c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) c = '_';
  return name;
}

}  // namespace primlabel::client::tools
