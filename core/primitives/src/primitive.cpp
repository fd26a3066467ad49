#include "primlabel/primitives/primitive.hpp"

#include <array>

#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel::primitives {
namespace {

constexpr std::array<std::string_view, 6> kNames = {"segment", "plane", "cylinder",
                                                    "sphere",  "torus", "line"};

}  // namespace

PrimitiveKind kind_of(const Model& model) { return static_cast<PrimitiveKind>(model.index()); }

std::string_view kind_name(PrimitiveKind kind) {
  const auto k = static_cast<std::size_t>(kind);
  return k < kNames.size() ? kNames[k] : std::string_view("segment");
}

std::optional<PrimitiveKind> kind_from_name(std::string_view name) {
  for (std::size_t k = 0; k < kNames.size(); ++k)
    if (kNames[k] == name) return static_cast<PrimitiveKind>(k);
  return std::nullopt;
}

PrimitiveKind model_for_class(std::uint32_t class_id) {
  switch (class_from_id(class_id).value_or(PrimitiveClass::kUnknown)) {
    case PrimitiveClass::kPlane:
      return PrimitiveKind::kPlane;
    case PrimitiveClass::kCylinderConvex:
    case PrimitiveClass::kCylinderConcave:
      return PrimitiveKind::kCylinder;
    case PrimitiveClass::kSphereConvex:
    case PrimitiveClass::kSphereConcave:
      return PrimitiveKind::kSphere;
    case PrimitiveClass::kTorusConvex:
    case PrimitiveClass::kTorusConcave:
      return PrimitiveKind::kTorus;
    case PrimitiveClass::kEdgeConvex:
    case PrimitiveClass::kEdgeConcave:
      return PrimitiveKind::kLine;
    case PrimitiveClass::kCorner:
    case PrimitiveClass::kUnknown:
      break;
  }
  return PrimitiveKind::kSegment;
}

}  // namespace primlabel::primitives
