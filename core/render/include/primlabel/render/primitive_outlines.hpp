#pragma once
// Fitted primitives as line drawings for render_png: a plane's rectangle, a cylinder's end
// circles, sides and axis, a sphere's three great circles, a torus's tube outline and axis, an
// edge's segment. A robot user sees at a glance what was fitted where.

#include <cstdint>
#include <span>
#include <vector>

#include "primlabel/primitives/primitive.hpp"
#include "primlabel/render/render.hpp"

namespace primlabel {

struct OutlineOptions {
  int circle_segments = 48;     // polyline vertices of a full circle
  double min_confidence = 0.0;  // primitives below it are left out
  double min_extent = 1e-4;     // m: sizes below it (or non-finite) are not drawn
};

// The outlines of every primitive with a model (segments of corners draw nothing), each in its
// class's colour darkened so it stands out over its own points.
std::vector<Overlay> primitive_outlines(std::span<const primitives::Primitive> fitted,
                                        const OutlineOptions& options = {});

}  // namespace primlabel
