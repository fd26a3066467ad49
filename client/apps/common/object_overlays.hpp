#pragma once
// The table-top stage's table and objects as overlays of the label picture, so `primlabel label
// --tabletop --png` shows what it found as primlabel-render --objects draws it: the table's hull
// in grey, each object's axis-aligned box in black with its id.

#include <vector>

#include "primlabel/render/render.hpp"
#include "primlabel/tabletop/tabletop_objects.hpp"

namespace primlabel::client::tools {

std::vector<Overlay> object_overlays(const tabletop::TabletopObjects& objects);

}  // namespace primlabel::client::tools
