#include "primlabel/tabletop/objects_json.hpp"

#include <stdexcept>

#include "primlabel/geometry/json_text.hpp"

namespace primlabel::tabletop {
namespace {

// Seven significant digits, as the primitives JSON: a micrometre at a metre.
json::Json number(double value) { return json::rounded(value, "%.7g"); }
template <typename Vector>
json::Json vector(const Vector& v) {
  json::Json out = json::Json::array();
  for (Eigen::Index k = 0; k < v.size(); ++k) out.push_back(number(double(v[k])));
  return out;
}
json::Json ids(const std::vector<std::uint32_t>& values) {
  json::Json out = json::Json::array();
  for (std::uint32_t v : values) out.push_back(v);
  return out;
}

[[noreturn]] void bad(const std::string& what) {
  throw std::invalid_argument("objects JSON: " + what);
}

const json::Json& member(const json::Json& object, const char* key, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) bad(where + ": no '" + key + "'");
  return *it;
}

double read_number(const json::Json& object, const char* key, const std::string& where) {
  const json::Json& value = member(object, key, where);
  if (!value.is_number()) bad(where + ": '" + key + "' is not a number");
  return value.get<double>();
}

std::size_t read_count(const json::Json& object, const char* key, const std::string& where) {
  const json::Json& value = member(object, key, where);
  if (!value.is_number_unsigned()) bad(where + ": '" + key + "' is not a count");
  return value.get<std::size_t>();
}

template <int N>
Eigen::Matrix<double, N, 1> read_vector(const json::Json& value, const std::string& what) {
  if (!value.is_array() || value.size() != std::size_t(N))
    bad(what + " is not a " + std::to_string(N) + "-vector");
  Eigen::Matrix<double, N, 1> v;
  for (int k = 0; k < N; ++k) {
    if (!value[k].is_number()) bad(what + " holds a non-number");
    v[k] = value[k].get<double>();
  }
  return v;
}

std::vector<std::uint32_t> read_ids(const json::Json& object, const std::string& where) {
  const json::Json& value = member(object, "primitives", where);
  if (!value.is_array()) bad(where + ": 'primitives' is not an array");
  std::vector<std::uint32_t> out;
  for (const json::Json& id : value) {
    if (!id.is_number_unsigned() || id.get<std::uint64_t>() >= kNoObject)
      bad(where + ": a primitive id is not a segment id");
    out.push_back(id.get<std::uint32_t>());
  }
  return out;
}

}  // namespace

std::string objects_json(const TabletopObjects& objects) {
  json::Json root;
  if (objects.table) {
    const TabletopTable& table = *objects.table;
    json::Json hull = json::Json::array();
    for (const Vec3f& p : table.hull) hull.push_back(vector(p));
    root["table"] = {{"plane", vector(table.plane)},
                     {"points", table.points},
                     {"hull", std::move(hull)},
                     {"primitives", ids(table.primitive_ids)}};
  } else {
    root["table"] = nullptr;
    root["message"] = objects.message;
  }
  json::Json list = json::Json::array();
  for (const TabletopObject& o : objects.objects)
    list.push_back({{"id", o.id},
                    {"points", o.points},
                    {"centroid", vector(o.centroid)},
                    {"bounds_min", vector(o.bounds_min)},
                    {"bounds_max", vector(o.bounds_max)},
                    {"height", number(o.height)},
                    {"primitives", ids(o.primitive_ids)}});
  root["objects"] = std::move(list);
  return json::dump(root, 1) + "\n";
}

TabletopObjects parse_objects_json(std::string_view text) {
  json::Json root;
  try {
    root = json::Json::parse(text);
  } catch (const json::Json::exception& e) {
    bad(e.what());
  }
  if (!root.is_object()) bad("not an object");
  TabletopObjects out;
  const json::Json& table = member(root, "table", "root");
  if (table.is_object()) {
    TabletopTable t;
    t.plane = read_vector<4>(member(table, "plane", "table"), "table plane").cast<float>();
    t.points = read_count(table, "points", "table");
    const json::Json& hull = member(table, "hull", "table");
    if (!hull.is_array()) bad("table: 'hull' is not an array");
    for (const json::Json& p : hull)
      t.hull.push_back(read_vector<3>(p, "a hull vertex").cast<float>());
    t.primitive_ids = read_ids(table, "table");
    out.table = std::move(t);
  } else if (table.is_null()) {
    const auto message = root.find("message");
    if (message != root.end() && message->is_string()) out.message = message->get<std::string>();
  } else {
    bad("'table' is neither an object nor null");
  }
  const json::Json& list = member(root, "objects", "root");
  if (!list.is_array()) bad("'objects' is not an array");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string where = "object " + std::to_string(i);
    const json::Json& o = list[i];
    if (!o.is_object()) bad(where + ": not an object");
    TabletopObject object;
    const std::size_t id = read_count(o, "id", where);
    if (id != i + 1)
      bad(where + ": id " + std::to_string(id) + ", expected " + std::to_string(i + 1));
    object.id = static_cast<std::uint32_t>(id);
    object.points = read_count(o, "points", where);
    object.centroid = read_vector<3>(member(o, "centroid", where), where + " centroid");
    object.bounds_min = read_vector<3>(member(o, "bounds_min", where), where + " bounds_min");
    object.bounds_max = read_vector<3>(member(o, "bounds_max", where), where + " bounds_max");
    object.height = read_number(o, "height", where);
    object.primitive_ids = read_ids(o, where);
    out.objects.push_back(std::move(object));
  }
  return out;
}

}  // namespace primlabel::tabletop
