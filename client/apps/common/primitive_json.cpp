#include "common/primitive_json.hpp"

#include <stdexcept>

#include "primlabel/primitives/primitives_json.hpp"

namespace primlabel::client::tools {

namespace {

primitives::Vec3d vec(const v1::Vec3d& v) { return {v.x(), v.y(), v.z()}; }

primitives::Model model_of(const v1::Primitive& m) {
  switch (m.model_case()) {
    case v1::Primitive::kPlane: {
      const v1::PlaneModel& p = m.plane();
      return primitives::PlaneModel{vec(p.normal()), p.offset(),   vec(p.center()), vec(p.axis_u()),
                                    vec(p.axis_v()), p.extent_u(), p.extent_v()};
    }
    case v1::Primitive::kCylinder: {
      const v1::CylinderModel& c = m.cylinder();
      return primitives::CylinderModel{vec(c.center()), vec(c.axis()), c.radius(), c.height()};
    }
    case v1::Primitive::kSphere:
      return primitives::SphereModel{vec(m.sphere().center()), m.sphere().radius()};
    case v1::Primitive::kTorus: {
      const v1::TorusModel& t = m.torus();
      return primitives::TorusModel{vec(t.center()), vec(t.axis()), t.major_radius(),
                                    t.minor_radius()};
    }
    case v1::Primitive::kLine: {
      const v1::LineModel& l = m.line();
      return primitives::LineModel{vec(l.center()), vec(l.direction()), l.length()};
    }
    case v1::Primitive::MODEL_NOT_SET:
      break;
  }
  return std::monostate{};
}

}  // namespace

primitives::Primitive from_message(const v1::Primitive& message) {
  primitives::Primitive primitive;
  primitive.class_id = message.class_id();
  primitive.model = model_of(message);
  if (std::uint32_t(primitive.kind()) != std::uint32_t(message.kind()))
    throw std::invalid_argument("primitive " + std::to_string(message.segment_id()) + ": kind " +
                                std::to_string(int(message.kind())) + " does not match its model");
  primitive.points = message.point_count();
  primitive.first_point = message.first_point();
  primitive.centroid = vec(message.centroid());
  primitive.bounds_min = vec(message.bounds_min());
  primitive.bounds_max = vec(message.bounds_max());
  primitive.inliers = message.inliers();
  primitive.rms = message.rms();
  primitive.confidence = message.confidence();
  return primitive;
}

std::vector<primitives::Primitive> primitives_of(const v1::LabelSummary& summary) {
  std::vector<primitives::Primitive> out;
  out.reserve(std::size_t(summary.primitives_size()));
  for (const v1::Primitive& message : summary.primitives()) out.push_back(from_message(message));
  return out;
}

std::string summary_primitives_json(const v1::LabelSummary& summary) {
  return primitives::primitives_json(primitives_of(summary));
}

}  // namespace primlabel::client::tools
