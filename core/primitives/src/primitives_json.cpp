#include "primlabel/primitives/primitives_json.hpp"

#include <stdexcept>
#include <string>

#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel::primitives {
namespace {

// Seven significant digits: a micrometre at a metre, more than any scan resolves.
json::Json number(double value) { return json::rounded(value, "%.7g"); }
json::Json vector(const Vec3d& v) {
  return json::Json::array({number(v.x()), number(v.y()), number(v.z())});
}

struct ModelWriter {
  json::Json& out;
  void operator()(const std::monostate&) const {}
  void operator()(const PlaneModel& m) const {
    out["normal"] = vector(m.normal);
    out["offset"] = number(m.offset);
    out["center"] = vector(m.center);
    out["axis_u"] = vector(m.axis_u);
    out["axis_v"] = vector(m.axis_v);
    out["extent_u"] = number(m.extent_u);
    out["extent_v"] = number(m.extent_v);
  }
  void operator()(const CylinderModel& m) const {
    out["center"] = vector(m.center);
    out["axis"] = vector(m.axis);
    out["radius"] = number(m.radius);
    out["height"] = number(m.height);
  }
  void operator()(const SphereModel& m) const {
    out["center"] = vector(m.center);
    out["radius"] = number(m.radius);
  }
  void operator()(const TorusModel& m) const {
    out["center"] = vector(m.center);
    out["axis"] = vector(m.axis);
    out["major_radius"] = number(m.major_radius);
    out["minor_radius"] = number(m.minor_radius);
  }
  void operator()(const LineModel& m) const {
    out["center"] = vector(m.center);
    out["direction"] = vector(m.direction);
    out["length"] = number(m.length);
  }
};

[[noreturn]] void bad(std::size_t index, const std::string& what) {
  throw std::invalid_argument("primitives JSON: primitive " + std::to_string(index) + ": " + what);
}

double read_number(const json::Json& object, const char* key, std::size_t index) {
  const auto it = object.find(key);
  if (it == object.end() || !it->is_number()) bad(index, std::string("no number '") + key + "'");
  return it->get<double>();
}

Vec3d read_vector(const json::Json& object, const char* key, std::size_t index) {
  const auto it = object.find(key);
  if (it == object.end() || !it->is_array() || it->size() != 3)
    bad(index, std::string("no 3-vector '") + key + "'");
  Vec3d v;
  for (int k = 0; k < 3; ++k) {
    if (!(*it)[k].is_number()) bad(index, std::string("'") + key + "' holds a non-number");
    v[k] = (*it)[k].get<double>();
  }
  return v;
}

Model read_model(PrimitiveKind kind, const json::Json& o, std::size_t i) {
  switch (kind) {
    case PrimitiveKind::kPlane:
      return PlaneModel{read_vector(o, "normal", i),  read_number(o, "offset", i),
                        read_vector(o, "center", i),  read_vector(o, "axis_u", i),
                        read_vector(o, "axis_v", i),  read_number(o, "extent_u", i),
                        read_number(o, "extent_v", i)};
    case PrimitiveKind::kCylinder:
      return CylinderModel{read_vector(o, "center", i), read_vector(o, "axis", i),
                           read_number(o, "radius", i), read_number(o, "height", i)};
    case PrimitiveKind::kSphere:
      return SphereModel{read_vector(o, "center", i), read_number(o, "radius", i)};
    case PrimitiveKind::kTorus:
      return TorusModel{read_vector(o, "center", i), read_vector(o, "axis", i),
                        read_number(o, "major_radius", i), read_number(o, "minor_radius", i)};
    case PrimitiveKind::kLine:
      return LineModel{read_vector(o, "center", i), read_vector(o, "direction", i),
                       read_number(o, "length", i)};
    case PrimitiveKind::kSegment:
      break;
  }
  return std::monostate{};
}

}  // namespace

json::Json to_json(const Primitive& p, std::size_t id) {
  const auto cls = class_from_id(p.class_id);
  json::Json out = {{"id", id},
                    {"kind", std::string(kind_name(p.kind()))},
                    {"class", cls ? std::string(name(*cls)) : std::to_string(p.class_id)},
                    {"class_id", p.class_id},
                    {"points", p.points},
                    {"first_point", p.first_point},
                    {"inliers", p.inliers},
                    {"rms", number(p.rms)},
                    {"confidence", json::rounded(p.confidence, "%.4f")},
                    {"centroid", vector(p.centroid)},
                    {"bounds_min", vector(p.bounds_min)},
                    {"bounds_max", vector(p.bounds_max)}};
  std::visit(ModelWriter{out}, p.model);
  return out;
}

std::string primitives_json(std::span<const Primitive> primitives) {
  json::Json list = json::Json::array();
  for (std::size_t i = 0; i < primitives.size(); ++i) list.push_back(to_json(primitives[i], i));
  return json::dump(json::Json{{"primitives", std::move(list)}}, 1) + "\n";
}

std::vector<Primitive> parse_primitives_json(std::string_view text) {
  json::Json root;
  try {
    root = json::Json::parse(text);
  } catch (const json::Json::exception& e) {
    throw std::invalid_argument(std::string("primitives JSON: ") + e.what());
  }
  if (!root.is_object() || !root.contains("primitives") || !root["primitives"].is_array())
    throw std::invalid_argument("primitives JSON: no \"primitives\" array");
  std::vector<Primitive> out;
  const json::Json& list = root["primitives"];
  for (std::size_t i = 0; i < list.size(); ++i) {
    const json::Json& o = list[i];
    if (!o.is_object()) bad(i, "not an object");
    const auto kind_it = o.find("kind");
    if (kind_it == o.end() || !kind_it->is_string()) bad(i, "no kind");
    const auto kind = kind_from_name(kind_it->get<std::string>());
    if (!kind) bad(i, "unknown kind '" + kind_it->get<std::string>() + "'");
    Primitive p;
    p.class_id = static_cast<std::uint32_t>(read_number(o, "class_id", i));
    p.points = static_cast<std::size_t>(read_number(o, "points", i));
    p.first_point = static_cast<std::uint32_t>(read_number(o, "first_point", i));
    p.inliers = static_cast<std::size_t>(read_number(o, "inliers", i));
    p.rms = read_number(o, "rms", i);
    p.confidence = read_number(o, "confidence", i);
    p.centroid = read_vector(o, "centroid", i);
    p.bounds_min = read_vector(o, "bounds_min", i);
    p.bounds_max = read_vector(o, "bounds_max", i);
    p.model = read_model(*kind, o, i);
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace primlabel::primitives
