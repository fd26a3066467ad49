#pragma once
// A matrix as a PNG-ready picture: cells shaded by a value in [0, 1] (white to dark blue) with
// optional text in each cell, row names on the left, column names (reading upwards) on top, axis
// titles and a title. Used for confusion matrices and class-distance matrices.

#include <string>
#include <vector>

#include "primlabel/render/raster.hpp"

namespace primlabel {

struct Heatmap {
  std::vector<std::string> row_names, column_names;
  std::vector<double> shades;          // rows x columns, row-major, in [0, 1]; NaN: no colour
  std::vector<std::string> cell_text;  // rows x columns, or empty for none
  std::string title;                   // above everything
  std::string row_axis, column_axis;   // e.g. "true class", "predicted class"
};

// Throws std::invalid_argument when the sizes do not match. `scale` enlarges the font.
Raster draw_heatmap(const Heatmap& heatmap, int scale = 2);

// The shade of `t` in [0, 1]: white through light blue to dark blue.
std::uint32_t blues(double t);

}  // namespace primlabel
