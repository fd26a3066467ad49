#include "primlabel/pipeline/domain.hpp"

#include <cmath>
#include <cstdio>

namespace primlabel::pipeline {

std::string spacing_warning(const TrainingSummary& training, float point_spacing) {
  const float low = training.point_spacing_min, high = training.point_spacing_max;
  if (!(low > 0.0f) || !(high >= low) || !(point_spacing > 0.0f) || !std::isfinite(point_spacing))
    return {};
  if (point_spacing >= low / kSpacingTolerance && point_spacing <= high * kSpacingTolerance)
    return {};
  char text[240];
  std::snprintf(
      text, sizeof text,
      "point spacing %.2f mm is %s than the %.2f-%.2f mm this model was trained for "
      "(more than %gx): labels are unreliable; use a model for this sensor or a voxel size",
      point_spacing * 1e3, point_spacing > high ? "sparser" : "denser", low * 1e3, high * 1e3,
      double(kSpacingTolerance));
  return text;
}

std::string noise_warning(const TrainingSummary& training, float surface_variation) {
  const float high = training.surface_variation_max;
  if (!(high > 0.0f) || !std::isfinite(surface_variation) ||
      surface_variation <= high * kSurfaceVariationTolerance)
    return {};
  char text[240];
  std::snprintf(
      text, sizeof text,
      "surface variation %.4f is %.1fx the noisiest training scene's %.4f (about %.1fx its "
      "range noise): labels are unreliable; use a model trained for this sensor",
      surface_variation, surface_variation / high, high, std::sqrt(surface_variation / high));
  return text;
}

std::string domain_warning(const TrainingSummary& training, float point_spacing,
                           float surface_variation) {
  const std::string spacing = spacing_warning(training, point_spacing);
  const std::string noise = noise_warning(training, surface_variation);
  if (spacing.empty()) return noise;
  return noise.empty() ? spacing : spacing + "; " + noise;
}

}  // namespace primlabel::pipeline
