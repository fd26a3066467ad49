#include "object_json.hpp"

#include "primlabel/tabletop/objects_json.hpp"

namespace primlabel::client::tools {

namespace {
Eigen::Vector3d vec(const v1::Vec3d& v) { return {v.x(), v.y(), v.z()}; }
}  // namespace

tabletop::TabletopObjects objects_of(const v1::LabelSummary& summary) {
  tabletop::TabletopObjects out;
  if (summary.has_table()) {
    const v1::TabletopTable& table = summary.table();
    tabletop::TabletopTable t;
    t.plane << vec(table.normal()).cast<float>(), float(table.offset());
    for (const v1::Vec3d& p : table.hull()) t.hull.push_back(vec(p).cast<float>());
    t.points = table.point_count();
    t.primitive_ids.assign(table.primitive_ids().begin(), table.primitive_ids().end());
    out.table = std::move(t);
  } else {
    out.message = summary.no_table_reason();
  }
  for (const v1::TabletopObject& o : summary.objects()) {
    tabletop::TabletopObject object;
    object.id = o.object_id();
    object.points = o.point_count();
    object.centroid = vec(o.centroid());
    object.bounds_min = vec(o.bounds_min());
    object.bounds_max = vec(o.bounds_max());
    object.height = o.height();
    object.primitive_ids.assign(o.primitive_ids().begin(), o.primitive_ids().end());
    out.objects.push_back(std::move(object));
  }
  return out;
}

std::string summary_objects_json(const v1::LabelSummary& summary) {
  return tabletop::objects_json(objects_of(summary));
}

std::vector<float> object_field(const std::vector<std::uint32_t>& object_ids) {
  std::vector<float> out(object_ids.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = object_ids[i] == tabletop::kNoObject ? -1.0f : float(object_ids[i]);
  return out;
}

}  // namespace primlabel::client::tools
