#pragma once
// The JSON form of table-top objects (primlabel label --objects, primlabel-eval --objects):
//   {"table": {"plane": [nx, ny, nz, d], "points": n, "hull": [[x, y, z], ...],
//              "primitives": [segment ids]} or null,
//    "message": why there is no table (only then),
//    "objects": [{"id": k, "points": n, "centroid": [x, y, z], "bounds_min": [...],
//                 "bounds_max": [...], "height": h, "primitives": [segment ids]}, ...]}
// Metres; primitive ids index the primitives JSON of the same call. Per-point ids are not in it.

#include <string>
#include <string_view>

#include "primlabel/tabletop/tabletop_objects.hpp"

namespace primlabel::tabletop {

std::string objects_json(const TabletopObjects& objects);

// Reads objects_json's output back (point_object stays empty); throws std::invalid_argument
// naming what is wrong.
TabletopObjects parse_objects_json(std::string_view text);

}  // namespace primlabel::tabletop
