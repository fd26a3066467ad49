// Training-curve PNG: its own tiny RGB raster (lines, axes) written with libpng.

#include "primlabel/pipeline/curve_plot.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace primlabel::pipeline {

namespace {

struct Raster {
  int width, height;
  std::vector<std::uint8_t> rgb;
  Raster(int w, int h) : width(w), height(h), rgb(std::size_t(w) * h * 3, 255) {}
  void set(int x, int y, std::uint32_t c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    std::uint8_t* p = &rgb[(std::size_t(y) * width + x) * 3];
    p[0] = std::uint8_t(c >> 16), p[1] = std::uint8_t(c >> 8), p[2] = std::uint8_t(c);
  }
  // Two pixels thick so the lines survive downscaling in viewers.
  void line(double x0, double y0, double x1, double y1, std::uint32_t c) {
    const int steps = int(std::max(std::abs(x1 - x0), std::abs(y1 - y0))) + 1;
    for (int s = 0; s <= steps; ++s) {
      const double t = double(s) / steps;
      const int x = int(std::lround(x0 + t * (x1 - x0))), y = int(std::lround(y0 + t * (y1 - y0)));
      set(x, y, c), set(x + 1, y, c), set(x, y + 1, c);
    }
  }
};

void write_png(const std::string& path, const Raster& raster) {
  FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) throw std::runtime_error(path + ": cannot be written");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    throw std::runtime_error(path + ": PNG could not be written");
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, raster.width, raster.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < raster.height; ++y)
    png_write_row(png, raster.rgb.data() + std::size_t(y) * raster.width * 3);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(file) != 0) throw std::runtime_error(path + ": cannot be written");
}

}  // namespace

void write_curve_png(const std::string& path, std::span<const crf::TrainingIteration> curve,
                     int width, int height) {
  Raster raster(width, height);
  const int left = 40, right = width - 20, top = 20, bottom = height - 30;
  raster.line(left, top, left, bottom, 0x000000);
  raster.line(left, bottom, right, bottom, 0x000000);
  for (int g = 1; g <= 4; ++g) {  // accuracy grid at 0.25 steps
    const double y = bottom - (bottom - top) * g / 4.0;
    for (int x = left; x < right; x += 6) raster.set(x, int(y), 0xC0C0C0);
  }
  if (!curve.empty()) {
    double lo = curve.front().objective, hi = lo;
    for (const auto& it : curve) lo = std::min(lo, it.objective), hi = std::max(hi, it.objective);
    const double span = hi > lo ? hi - lo : 1.0;
    const double n = std::max<double>(1, double(curve.size() - 1));
    auto x_of = [&](std::size_t i) { return left + (right - left) * double(i) / n; };
    auto y_of = [&](double v) { return bottom - (bottom - top) * std::clamp(v, 0.0, 1.0); };
    for (std::size_t i = 1; i < curve.size(); ++i) {
      const auto &a = curve[i - 1], &b = curve[i];
      raster.line(x_of(i - 1), y_of((a.objective - lo) / span), x_of(i),
                  y_of((b.objective - lo) / span), kCurveObjectiveRgb);
      raster.line(x_of(i - 1), y_of(a.train_accuracy), x_of(i), y_of(b.train_accuracy),
                  kCurveTrainRgb);
      if (std::isfinite(a.validation_accuracy) && std::isfinite(b.validation_accuracy))
        raster.line(x_of(i - 1), y_of(a.validation_accuracy), x_of(i), y_of(b.validation_accuracy),
                    kCurveValidationRgb);
    }
  }
  write_png(path, raster);
}

}  // namespace primlabel::pipeline
