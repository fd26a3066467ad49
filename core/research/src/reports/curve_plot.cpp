// Training-curve PNG: lines and axes on a Raster.

#include "primlabel/research/curve_plot.hpp"

#include <algorithm>
#include <cmath>

#include "primlabel/render/raster.hpp"

namespace primlabel::research {

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
  raster.write_png(path);
}

}  // namespace primlabel::research
