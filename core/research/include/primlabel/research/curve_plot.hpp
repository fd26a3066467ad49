#pragma once
// A small line plot of a training curve (Rusu et al. 2009, Fig. 9) as PNG: accuracies on a fixed
// 0..1 axis, the objective rescaled to its own range. No text: the colours are fixed (objective
// grey, training accuracy blue, validation accuracy orange).

#include <span>
#include <string>

#include "primlabel/crf/training.hpp"

namespace primlabel::research {

inline constexpr std::uint32_t kCurveObjectiveRgb = 0x808080;
inline constexpr std::uint32_t kCurveTrainRgb = 0x1F77B4;
inline constexpr std::uint32_t kCurveValidationRgb = 0xFF7F0E;

// Throws std::runtime_error naming the path when it cannot be written.
void write_curve_png(const std::string& path, std::span<const crf::TrainingIteration> curve,
                     int width = 640, int height = 400);

}  // namespace primlabel::research
