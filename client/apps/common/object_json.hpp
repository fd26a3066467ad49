#pragma once
// The summary's table and objects (v1::TabletopTable, v1::TabletopObject) as the core's
// tabletop::TabletopObjects, so `primlabel label --objects` writes exactly the JSON of
// `primlabel-eval --objects` (objects_json.hpp).

#include <string>

#include "primlabel/tabletop/tabletop_objects.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::client::tools {

// Without the per-point ids (point_object stays empty).
tabletop::TabletopObjects objects_of(const v1::LabelSummary& summary);
std::string summary_objects_json(const v1::LabelSummary& summary);

// The per-point object ids as the float field `object` writes them: the id, -1 for neither table
// nor object (0xFFFFFFFF has no exact float).
std::vector<float> object_field(const std::vector<std::uint32_t>& object_ids);

}  // namespace primlabel::client::tools
