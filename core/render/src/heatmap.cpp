// Heat-map layout: title, column names standing upright above the cells, row names to the left,
// cells sized to their longest text.

#include "primlabel/render/heatmap.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace primlabel {

std::uint32_t blues(double t) {
  // ColorBrewer "Blues" end points and middle, interpolated linearly.
  static constexpr std::uint32_t kStops[] = {0xF7FBFF, 0x6BAED6, 0x08306B};
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0);
  const double at = t * 2.0;
  const int i = std::min(int(at), 1);
  const double f = at - i;
  auto channel = [&](int shift) {
    const double a = (kStops[i] >> shift) & 0xFF, b = (kStops[i + 1] >> shift) & 0xFF;
    return std::uint32_t(std::lround(a + f * (b - a))) << shift;
  };
  return channel(16) | channel(8) | channel(0);
}

Raster draw_heatmap(const Heatmap& h, int scale) {
  const std::size_t rows = h.row_names.size(), cols = h.column_names.size();
  if (rows == 0 || cols == 0 || h.shades.size() != rows * cols ||
      (!h.cell_text.empty() && h.cell_text.size() != rows * cols))
    throw std::invalid_argument("heat map: names, shades and cell texts do not match");
  const int margin = 8 * scale, gap = 3 * scale, line = Raster::text_height(scale) + gap;
  auto widest = [&](const std::vector<std::string>& texts) {
    int w = 0;
    for (const std::string& t : texts) w = std::max(w, Raster::text_width(t, scale));
    return w;
  };
  const int cell_w = std::max(widest(h.cell_text) + 2 * gap, line + 2 * gap);
  const int cell_h = line + 2 * gap;
  const int row_names_w = widest(h.row_names) + gap;
  const int column_names_h = widest(h.column_names) + gap;
  const int title_h = h.title.empty() ? 0 : line + gap;
  const int column_axis_h = h.column_axis.empty() ? 0 : line;
  const int row_axis_w = h.row_axis.empty() ? 0 : line + gap;

  const int grid_x = margin + row_axis_w + row_names_w;
  const int grid_y = margin + title_h + column_axis_h + column_names_h;
  const int grid_w = int(cols) * cell_w, grid_h = int(rows) * cell_h;
  const int width =
      std::max(grid_x + grid_w + margin, 2 * margin + Raster::text_width(h.title, scale));
  Raster raster(width, grid_y + grid_h + margin);

  const std::uint32_t ink = 0x202020;
  if (!h.title.empty()) raster.text(margin, margin, h.title, ink, scale);
  if (!h.column_axis.empty())
    raster.text(grid_x + (grid_w - Raster::text_width(h.column_axis, scale)) / 2, margin + title_h,
                h.column_axis, ink, scale);
  if (!h.row_axis.empty())
    raster.text_up(margin, grid_y + (grid_h - Raster::text_width(h.row_axis, scale)) / 2,
                   h.row_axis, ink, scale);
  for (std::size_t c = 0; c < cols; ++c)
    raster.text_up(grid_x + int(c) * cell_w + (cell_w - Raster::text_height(scale)) / 2,
                   grid_y - gap - Raster::text_width(h.column_names[c], scale), h.column_names[c],
                   ink, scale);
  for (std::size_t r = 0; r < rows; ++r) {
    const int y = grid_y + int(r) * cell_h;
    raster.text(grid_x - gap - Raster::text_width(h.row_names[r], scale),
                y + (cell_h - Raster::text_height(scale)) / 2, h.row_names[r], ink, scale);
    for (std::size_t c = 0; c < cols; ++c) {
      const int x = grid_x + int(c) * cell_w;
      const double shade = h.shades[r * cols + c];
      const std::uint32_t fill = std::isfinite(shade) ? blues(shade) : 0xFFFFFF;
      raster.fill(x, y, cell_w, cell_h, fill);
      if (h.cell_text.empty()) continue;
      const std::string& text = h.cell_text[r * cols + c];
      raster.text(x + (cell_w - Raster::text_width(text, scale)) / 2,
                  y + (cell_h - Raster::text_height(scale)) / 2, text, contrasting_text_color(fill),
                  scale);
    }
  }
  // Grid lines over the cells.
  for (std::size_t r = 0; r <= rows; ++r)
    raster.fill(grid_x, grid_y + int(r) * cell_h, grid_w + 1, 1, 0xB0B0B0);
  for (std::size_t c = 0; c <= cols; ++c)
    raster.fill(grid_x + int(c) * cell_w, grid_y, 1, grid_h + 1, 0xB0B0B0);
  return raster;
}

}  // namespace primlabel
