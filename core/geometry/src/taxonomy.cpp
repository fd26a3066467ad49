#include "primlabel/geometry/taxonomy.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "primlabel/geometry/atomic_file.hpp"

namespace primlabel {
namespace {

struct ClassInfo {
  PrimitiveClass cls;
  std::string_view name;
  std::uint32_t rgb;
};

// Index = id. Colours: planes grey-blue, cylinders green, edges orange/red, corner magenta,
// tori yellow/brown, spheres cyan/blue; the concave member of a pair is the darker/cooler one.
constexpr std::array<ClassInfo, kPrimitiveClassCount> kClasses = {{
    {PrimitiveClass::kUnknown, "unknown", 0x9A9A9A},
    {PrimitiveClass::kPlane, "plane", 0x8FA8C8},
    {PrimitiveClass::kCylinderConvex, "cylinder-convex", 0x3CB44B},
    {PrimitiveClass::kCylinderConcave, "cylinder-concave", 0x1B6B2F},
    {PrimitiveClass::kEdgeConvex, "edge-convex", 0xF58231},
    {PrimitiveClass::kEdgeConcave, "edge-concave", 0xC8102E},
    {PrimitiveClass::kCorner, "corner", 0xE6199B},
    {PrimitiveClass::kTorusConvex, "torus-convex", 0xFFD60A},
    {PrimitiveClass::kTorusConcave, "torus-concave", 0x9A6324},
    {PrimitiveClass::kSphereConvex, "sphere-convex", 0x42D4F4},
    {PrimitiveClass::kSphereConcave, "sphere-concave", 0x2846C8},
}};

std::string normalized(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '_' || c == ' ') c = '-';
    out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string known_names() {
  std::string out;
  for (const ClassInfo& info : kClasses) {
    out += out.empty() ? "" : ", ";
    out += info.name;
  }
  return out;
}

}  // namespace

const std::vector<PrimitiveClass>& all_classes() {
  static const std::vector<PrimitiveClass> classes = [] {
    std::vector<PrimitiveClass> out;
    for (const ClassInfo& info : kClasses) out.push_back(info.cls);
    return out;
  }();
  return classes;
}

std::optional<PrimitiveClass> class_from_id(std::uint32_t id) {
  if (id >= kPrimitiveClassCount) return std::nullopt;
  return kClasses[id].cls;
}

std::string_view name(PrimitiveClass c) {
  const std::uint32_t id = class_id(c);
  return id < kPrimitiveClassCount ? kClasses[id].name : std::string_view("invalid");
}

std::optional<PrimitiveClass> from_name(std::string_view text) {
  const std::string key = normalized(trim(text));
  if (key == "other" || key == "unknown/other" || key == "unknown-other")
    return PrimitiveClass::kUnknown;
  for (const ClassInfo& info : kClasses)
    if (key == info.name) return info.cls;
  return std::nullopt;
}

std::uint32_t color(PrimitiveClass c) {
  const std::uint32_t id = class_id(c);
  return id < kPrimitiveClassCount ? kClasses[id].rgb : 0x000000;
}

ClassMap ClassMap::taxonomy() {
  ClassMap map;
  for (const ClassInfo& info : kClasses) map.add(class_id(info.cls), std::string(info.name));
  return map;
}

void ClassMap::add(std::uint32_t id, const std::string& class_name) {
  const std::optional<PrimitiveClass> cls = from_name(class_name);
  if (!cls)
    throw std::invalid_argument("'" + class_name +
                                "' is not a primitive class (known: " + known_names() + ")");
  auto at = std::lower_bound(entries_.begin(), entries_.end(), id,
                             [](const Entry& e, std::uint32_t v) { return e.id < v; });
  if (at != entries_.end() && at->id == id)
    throw std::invalid_argument("label " + std::to_string(id) + " is listed twice");
  entries_.insert(at, Entry{id, class_name, *cls});
}

ClassMap ClassMap::parse(std::string_view text, const std::string& source) {
  ClassMap map;
  std::istringstream in{std::string(text)};
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::string_view content = line;
    if (const auto hash = content.find('#'); hash != std::string_view::npos)
      content = content.substr(0, hash);
    content = trim(content);
    if (content.empty()) continue;
    const std::string where = source + ":" + std::to_string(line_number) + ": ";
    std::size_t digits = 0;
    while (digits < content.size() && std::isdigit(static_cast<unsigned char>(content[digits])))
      ++digits;
    const char next = digits < content.size() ? content[digits] : '\0';
    const bool separated = std::isspace(static_cast<unsigned char>(next)) ||
                           std::string_view(",:=").find(next) != std::string_view::npos;
    std::string_view rest = trim(content.substr(digits));
    if (!rest.empty() && std::string_view(",:=").find(rest.front()) != std::string_view::npos)
      rest = trim(rest.substr(1));
    if (digits == 0 || digits > 9 || !separated || rest.empty())
      throw std::invalid_argument(where + "expected '<label id> <class name>', got '" +
                                  std::string(content) + "'");
    const auto id = static_cast<std::uint32_t>(std::stoul(std::string(content.substr(0, digits))));
    try {
      map.add(id, std::string(rest));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + e.what());
    }
  }
  return map;
}

std::string ClassMap::to_text() const {
  std::string out;
  for (const Entry& e : entries_) out += std::to_string(e.id) + " " + e.name + "\n";
  return out;
}

const ClassMap::Entry* ClassMap::find(std::uint32_t id) const {
  auto at = std::lower_bound(entries_.begin(), entries_.end(), id,
                             [](const Entry& e, std::uint32_t v) { return e.id < v; });
  return at != entries_.end() && at->id == id ? &*at : nullptr;
}

std::optional<PrimitiveClass> ClassMap::class_of(std::uint32_t id) const {
  const Entry* e = find(id);
  if (!e) return std::nullopt;
  return e->cls;
}

ClassMap read_class_map(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open class map");
  std::stringstream text;
  text << in.rdbuf();
  ClassMap map = ClassMap::parse(text.str(), path);
  if (map.empty()) throw std::invalid_argument(path + ": class map lists no classes");
  return map;
}

void write_class_map(const std::string& path, const ClassMap& map) {
  try {
    atomic_write_file(path, map.to_text());
  } catch (const AtomicWriteError& e) {
    throw std::runtime_error(std::string("cannot write class map: ") + e.what());
  }
}

}  // namespace primlabel
