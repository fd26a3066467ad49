#include "primlabel/service/object_messages.hpp"

namespace primlabel::service {

namespace {

template <typename Vector>
void set(const Vector& v, v1::Vec3d& message) {
  message.set_x(double(v.x()));
  message.set_y(double(v.y()));
  message.set_z(double(v.z()));
}

}  // namespace

void to_message(const tabletop::TabletopTable& table, v1::TabletopTable& message) {
  set(table.plane.head<3>(), *message.mutable_normal());
  message.set_offset(double(table.plane[3]));
  for (const Vec3f& p : table.hull) set(p, *message.add_hull());
  message.set_point_count(table.points);
  message.mutable_primitive_ids()->Add(table.primitive_ids.begin(), table.primitive_ids.end());
}

void to_message(const tabletop::TabletopObject& object, v1::TabletopObject& message) {
  message.set_object_id(object.id);
  message.set_point_count(object.points);
  set(object.centroid, *message.mutable_centroid());
  set(object.bounds_min, *message.mutable_bounds_min());
  set(object.bounds_max, *message.mutable_bounds_max());
  message.set_height(object.height);
  message.mutable_primitive_ids()->Add(object.primitive_ids.begin(), object.primitive_ids.end());
}

void add_objects(const tabletop::TabletopObjects& objects, v1::LabelSummary& summary) {
  if (objects.table)
    to_message(*objects.table, *summary.mutable_table());
  else
    summary.set_no_table_reason(objects.message);
  summary.mutable_objects()->Reserve(int(objects.objects.size()));
  for (const tabletop::TabletopObject& object : objects.objects)
    to_message(object, *summary.add_objects());
}

}  // namespace primlabel::service
