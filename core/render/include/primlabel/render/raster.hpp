#pragma once
// An RGB picture to draw charts on (rectangles, lines, text in the built-in 5x7 font, whose
// g, j, p, q and y descend one row below the baseline: text_height covers them) and write
// as PNG with libpng. The point-cloud renderer, the training curve, the confusion matrix and the
// Fig. 4 plots all draw on it.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace primlabel {

class Raster {
 public:
  // Throws std::invalid_argument unless 1..16384 pixels a side.
  Raster(int width, int height, std::uint32_t background = 0xFFFFFF);

  int width() const { return width_; }
  int height() const { return height_; }
  std::uint32_t at(int x, int y) const { return rgb_[std::size_t(y) * width_ + x]; }
  std::vector<std::uint32_t>& pixels() { return rgb_; }  // 0xRRGGBB, row-major

  // Drawing clips at the edges.
  void set(int x, int y, std::uint32_t rgb);
  void fill(int x, int y, int w, int h, std::uint32_t rgb);
  void frame(int x, int y, int w, int h, std::uint32_t rgb);  // a one-pixel outline
  // `thickness` pixels wide, so thin lines survive downscaling in viewers.
  void line(double x0, double y0, double x1, double y1, std::uint32_t rgb, int thickness = 2);
  // Text with its top-left corner at (x, y), each font pixel `scale` x `scale` pixels.
  void text(int x, int y, std::string_view s, std::uint32_t rgb, int scale = 1);
  // Text reading bottom to top, its baseline along x + height, ending at row y.
  void text_up(int x, int y, std::string_view s, std::uint32_t rgb, int scale = 1);
  static int text_width(std::string_view s, int scale = 1);
  static int text_height(int scale = 1);

  // Throws std::runtime_error "cannot write PNG '<path>': <reason>".
  void write_png(const std::string& path) const;

 private:
  int width_, height_;
  std::vector<std::uint32_t> rgb_;
};

// Black or white, whichever reads better on `background`.
std::uint32_t contrasting_text_color(std::uint32_t background);

}  // namespace primlabel
