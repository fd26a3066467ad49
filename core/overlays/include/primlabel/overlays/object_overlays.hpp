#pragma once
// The table-top stage's table and objects as overlays of a rendered picture, the same in
// `primlabel label --tabletop --png` and `primlabel-render --objects`: the table's hull in grey,
// each object's axis-aligned box in black with its id.

#include <vector>

#include "primlabel/render/render.hpp"
#include "primlabel/tabletop/tabletop_objects.hpp"

namespace primlabel {

// The table's hull (when there is a table) and a box "object <id>" per object with points.
std::vector<Overlay> object_overlays(const tabletop::TabletopObjects& objects);

}  // namespace primlabel
