#pragma once
// Fitted primitive instances as LabelSummary.primitives: the one place the core's
// primitives::Primitive becomes a v1::Primitive (the kinds' numbers are shared by both).

#include <cstdint>
#include <span>

#include "primlabel/primitives/primitive.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::service {

void to_message(const primitives::Primitive& primitive, std::uint32_t segment_id,
                v1::Primitive& message);

// Appends primitives[s] as segment s.
void add_primitives(std::span<const primitives::Primitive> primitives, v1::LabelSummary& summary);

}  // namespace primlabel::service
