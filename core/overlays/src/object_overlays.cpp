#include "primlabel/overlays/object_overlays.hpp"

#include <string>

#include "primlabel/render/box_outlines.hpp"

namespace primlabel {

std::vector<Overlay> object_overlays(const tabletop::TabletopObjects& objects) {
  std::vector<LabeledBox> boxes;
  for (const tabletop::TabletopObject& o : objects.objects)
    if (o.points > 0)
      boxes.push_back({o.bounds_min.cast<float>(), o.bounds_max.cast<float>(),
                       "object " + std::to_string(o.id)});
  return table_top_outlines(objects.table ? objects.table->hull : std::vector<Vec3f>{}, boxes);
}

}  // namespace primlabel
