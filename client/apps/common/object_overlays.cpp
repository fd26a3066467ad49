#include "object_overlays.hpp"

#include <string>

#include "primlabel/render/box_outlines.hpp"

namespace primlabel::client::tools {

std::vector<Overlay> object_overlays(const tabletop::TabletopObjects& objects) {
  std::vector<Overlay> out;
  if (objects.table && objects.table->hull.size() >= 2) {
    Overlay hull;
    hull.points = objects.table->hull;
    hull.rgb = 0x808080;
    hull.closed = true;
    out.push_back(std::move(hull));
  }
  for (const tabletop::TabletopObject& o : objects.objects) {
    if (o.points == 0) continue;
    for (Overlay& edge : box_outline(o.bounds_min.cast<float>(), o.bounds_max.cast<float>(),
                                     0x000000, "object " + std::to_string(o.id)))
      out.push_back(std::move(edge));
  }
  return out;
}

}  // namespace primlabel::client::tools
