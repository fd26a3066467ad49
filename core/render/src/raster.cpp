// Raster drawing and the one libpng writer of the project.

#include "primlabel/render/raster.hpp"

#include <png.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "font5x7.hpp"
#include "primlabel/geometry/atomic_file.hpp"

namespace primlabel {

using render_detail::glyph;
using render_detail::kGlyphHeight;
using render_detail::kGlyphWidth;

Raster::Raster(int width, int height, std::uint32_t background) : width_(width), height_(height) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw std::invalid_argument("raster: image size must be 1..16384 pixels a side");
  rgb_.assign(std::size_t(width) * height, background & 0xFFFFFF);
}

void Raster::set(int x, int y, std::uint32_t rgb) {
  if (x >= 0 && y >= 0 && x < width_ && y < height_) rgb_[std::size_t(y) * width_ + x] = rgb;
}

void Raster::fill(int x0, int y0, int w, int h, std::uint32_t rgb) {
  const int x_end = std::min(x0 + w, width_), y_end = std::min(y0 + h, height_);
  for (int y = std::max(y0, 0); y < y_end; ++y)
    for (int x = std::max(x0, 0); x < x_end; ++x) rgb_[std::size_t(y) * width_ + x] = rgb;
}

void Raster::frame(int x, int y, int w, int h, std::uint32_t rgb) {
  fill(x, y, w, 1, rgb);
  fill(x, y + h - 1, w, 1, rgb);
  fill(x, y, 1, h, rgb);
  fill(x + w - 1, y, 1, h, rgb);
}

void Raster::line(double x0, double y0, double x1, double y1, std::uint32_t rgb, int thickness) {
  const int steps = int(std::max(std::abs(x1 - x0), std::abs(y1 - y0))) + 1;
  for (int s = 0; s <= steps; ++s) {
    const double t = double(s) / steps;
    const int x = int(std::lround(x0 + t * (x1 - x0))), y = int(std::lround(y0 + t * (y1 - y0)));
    set(x, y, rgb);
    for (int d = 1; d < thickness; ++d) set(x + d, y, rgb), set(x, y + d, rgb);
  }
}

void Raster::text(int x, int y, std::string_view s, std::uint32_t rgb, int scale) {
  for (char c : s) {
    const std::uint8_t* columns = glyph(c);
    for (int col = 0; col < kGlyphWidth; ++col)
      for (int row = 0; row < kGlyphHeight; ++row)
        if (columns[col] >> row & 1) fill(x + col * scale, y + row * scale, scale, scale, rgb);
    x += (kGlyphWidth + 1) * scale;
  }
}

void Raster::text_up(int x, int y, std::string_view s, std::uint32_t rgb, int scale) {
  int bottom = y + text_width(s, scale);  // the first character at the bottom
  for (char c : s) {
    const std::uint8_t* columns = glyph(c);
    for (int col = 0; col < kGlyphWidth; ++col)
      for (int row = 0; row < kGlyphHeight; ++row)
        if (columns[col] >> row & 1)
          fill(x + row * scale, bottom - (col + 1) * scale, scale, scale, rgb);
    bottom -= (kGlyphWidth + 1) * scale;
  }
}

int Raster::text_width(std::string_view s, int scale) {
  return static_cast<int>(s.size()) * (kGlyphWidth + 1) * scale;
}

int Raster::text_height(int scale) { return kGlyphHeight * scale; }

void Raster::write_png(const std::string& path) const {
  const std::string what = "cannot write PNG '" + path + "': ";
  try {
    atomic_write_file(path, [&](FILE* file) {
      png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
      png_infop info = png ? png_create_info_struct(png) : nullptr;
      if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        throw std::runtime_error(what + "out of memory");
      }
      std::vector<png_byte> row(std::size_t(width_) * 3);
      if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        throw std::runtime_error(what + "libpng failed (disk full?)");
      }
      png_init_io(png, file);
      png_set_IHDR(png, info, width_, height_, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                   PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
      png_write_info(png, info);
      for (int y = 0; y < height_; ++y) {
        for (int x = 0; x < width_; ++x) {
          const std::uint32_t c = rgb_[std::size_t(y) * width_ + x];
          row[3 * x] = png_byte(c >> 16);
          row[3 * x + 1] = png_byte(c >> 8);
          row[3 * x + 2] = png_byte(c);
        }
        png_write_row(png, row.data());
      }
      png_write_end(png, nullptr);
      png_destroy_write_struct(&png, &info);
    });
  } catch (const AtomicWriteError& e) {
    throw std::runtime_error(what + e.what());
  }
}

std::uint32_t contrasting_text_color(std::uint32_t background) {
  const double r = (background >> 16) & 0xFF, g = (background >> 8) & 0xFF, b = background & 0xFF;
  return 0.299 * r + 0.587 * g + 0.114 * b > 140 ? 0x000000 : 0xFFFFFF;
}

}  // namespace primlabel
