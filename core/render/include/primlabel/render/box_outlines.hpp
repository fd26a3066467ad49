#pragma once
// Axis-aligned boxes as line drawings for render_png, e.g. the bounds of table-top objects: the
// bottom and top rectangles and the four vertical edges, with an optional label at a corner.

#include <cstdint>
#include <string>
#include <vector>

#include "primlabel/render/render.hpp"

namespace primlabel {

// The 6 polylines of the box between `low` and `high` in `rgb`; `label` (if any) is drawn at the
// top corner nearest `low`. Nothing for a box with a non-finite corner.
std::vector<Overlay> box_outline(const Vec3f& low, const Vec3f& high, std::uint32_t rgb,
                                 const std::string& label = {});

// A table top as the label picture shows it: the table's hull (when it has 2 points or more) in
// grey, each box in black with its label.
struct LabeledBox {
  Vec3f low, high;
  std::string label;
};
std::vector<Overlay> table_top_outlines(const std::vector<Vec3f>& hull,
                                        const std::vector<LabeledBox>& boxes);

}  // namespace primlabel
