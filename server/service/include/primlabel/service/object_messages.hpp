#pragma once
// Table-top objects as LabelSummary.table, objects and no_table_reason: the one place the core's
// tabletop::TabletopObjects becomes v1 messages.

#include "primlabel/tabletop/tabletop_objects.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::service {

void to_message(const tabletop::TabletopTable& table, v1::TabletopTable& message);
void to_message(const tabletop::TabletopObject& object, v1::TabletopObject& message);

// Sets the summary's table (or no_table_reason) and appends every object in id order.
void add_objects(const tabletop::TabletopObjects& objects, v1::LabelSummary& summary);

}  // namespace primlabel::service
