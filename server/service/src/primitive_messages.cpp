#include "primlabel/service/primitive_messages.hpp"

#include <variant>

namespace primlabel::service {

namespace {

void set(const primitives::Vec3d& v, v1::Vec3d& message) {
  message.set_x(v.x());
  message.set_y(v.y());
  message.set_z(v.z());
}

void set_model(const primitives::PlaneModel& plane, v1::Primitive& message) {
  v1::PlaneModel& out = *message.mutable_plane();
  set(plane.normal, *out.mutable_normal());
  out.set_offset(plane.offset);
  set(plane.center, *out.mutable_center());
  set(plane.axis_u, *out.mutable_axis_u());
  set(plane.axis_v, *out.mutable_axis_v());
  out.set_extent_u(plane.extent_u);
  out.set_extent_v(plane.extent_v);
}

void set_model(const primitives::CylinderModel& cylinder, v1::Primitive& message) {
  v1::CylinderModel& out = *message.mutable_cylinder();
  set(cylinder.center, *out.mutable_center());
  set(cylinder.axis, *out.mutable_axis());
  out.set_radius(cylinder.radius);
  out.set_height(cylinder.height);
}

void set_model(const primitives::SphereModel& sphere, v1::Primitive& message) {
  v1::SphereModel& out = *message.mutable_sphere();
  set(sphere.center, *out.mutable_center());
  out.set_radius(sphere.radius);
}

void set_model(const primitives::TorusModel& torus, v1::Primitive& message) {
  v1::TorusModel& out = *message.mutable_torus();
  set(torus.center, *out.mutable_center());
  set(torus.axis, *out.mutable_axis());
  out.set_major_radius(torus.major_radius);
  out.set_minor_radius(torus.minor_radius);
}

void set_model(const primitives::LineModel& line, v1::Primitive& message) {
  v1::LineModel& out = *message.mutable_line();
  set(line.center, *out.mutable_center());
  set(line.direction, *out.mutable_direction());
  out.set_length(line.length);
}

void set_model(std::monostate, v1::Primitive&) {}

}  // namespace

void to_message(const primitives::Primitive& primitive, std::uint32_t segment_id,
                v1::Primitive& message) {
  static_assert(std::uint32_t(primitives::PrimitiveKind::kLine) == v1::PRIMITIVE_LINE &&
                std::uint32_t(primitives::PrimitiveKind::kTorus) == v1::PRIMITIVE_TORUS &&
                std::uint32_t(primitives::PrimitiveKind::kSphere) == v1::PRIMITIVE_SPHERE &&
                std::uint32_t(primitives::PrimitiveKind::kCylinder) == v1::PRIMITIVE_CYLINDER &&
                std::uint32_t(primitives::PrimitiveKind::kPlane) == v1::PRIMITIVE_PLANE &&
                std::uint32_t(primitives::PrimitiveKind::kSegment) == v1::PRIMITIVE_SEGMENT);
  message.set_segment_id(segment_id);
  message.set_kind(static_cast<v1::PrimitiveKind>(primitive.kind()));
  message.set_class_id(primitive.class_id);
  std::visit([&](const auto& model) { set_model(model, message); }, primitive.model);
  message.set_point_count(primitive.points);
  message.set_first_point(primitive.first_point);
  message.set_inliers(primitive.inliers);
  message.set_rms(primitive.rms);
  message.set_confidence(primitive.confidence);
  set(primitive.centroid, *message.mutable_centroid());
  set(primitive.bounds_min, *message.mutable_bounds_min());
  set(primitive.bounds_max, *message.mutable_bounds_max());
}

void add_primitives(std::span<const primitives::Primitive> primitives, v1::LabelSummary& summary) {
  summary.mutable_primitives()->Reserve(int(primitives.size()));
  for (std::size_t s = 0; s < primitives.size(); ++s)
    to_message(primitives[s], static_cast<std::uint32_t>(s), *summary.add_primitives());
}

}  // namespace primlabel::service
