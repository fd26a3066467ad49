#pragma once
// The summary's primitives (v1::Primitive) as the core's primitives::Primitive, so `primlabel
// label --primitives` writes exactly the JSON of `primlabel-eval --primitives`.

#include <string>
#include <vector>

#include "primlabel/primitives/primitive.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::client::tools {

// Throws std::invalid_argument for a message whose kind and model disagree.
primitives::Primitive from_message(const v1::Primitive& message);
std::vector<primitives::Primitive> primitives_of(const v1::LabelSummary& summary);
// {"primitives": [...]} of the summary's primitives (primitives_json.hpp).
std::string summary_primitives_json(const v1::LabelSummary& summary);

}  // namespace primlabel::client::tools
