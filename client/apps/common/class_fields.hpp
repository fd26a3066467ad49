#pragma once
// The names of per-class output fields, one spelling in every format (PCD, PLY, the ROS node's
// PointCloud2): `prob_<class>` with the class name's characters outside [A-Za-z0-9_] as '_'
// ("prob_cylinder_convex"; one '_' per UTF-8 character), or `prob_<id>` for a class without a
// name. The Python client spells them alike (tests/data/probability_field_names.tsv holds the
// cases both check). C++17: the ROS nodes include it.

#include <cctype>
#include <cstdint>
#include <string>

namespace primlabel::client::tools {

inline std::string probability_field_name(const std::string& class_name, std::uint32_t class_id) {
  if (class_name.empty()) return "prob_" + std::to_string(class_id);
  std::string name = "prob_";
  for (const char c : class_name) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte & 0xC0) == 0x80) continue;  // a UTF-8 continuation: one '_' per character
    name += (byte < 0x80 && (std::isalnum(byte) || c == '_')) ? c : '_';
  }
  return name;
}

}  // namespace primlabel::client::tools
