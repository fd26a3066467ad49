#include "primlabel/pipeline/domain.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_spacing.hpp"

namespace primlabel::pipeline {

namespace {
// Whether the model recorded its spacing range and the cloud has a spacing to hold against it.
bool comparable(const TrainingSummary& training, float point_spacing) {
  const float low = training.point_spacing_min, high = training.point_spacing_max;
  return low > 0.0f && high >= low && point_spacing > 0.0f && std::isfinite(point_spacing);
}
}  // namespace

bool sparser_than_trained(const TrainingSummary& training, float point_spacing) {
  return comparable(training, point_spacing) &&
         point_spacing > training.point_spacing_max * kSpacingTolerance;
}

std::string spacing_warning(const TrainingSummary& training, float point_spacing) {
  const float low = training.point_spacing_min, high = training.point_spacing_max;
  if (!comparable(training, point_spacing)) return {};
  const bool sparser = sparser_than_trained(training, point_spacing);
  if (!sparser && point_spacing >= low / kSpacingTolerance) return {};
  char text[240];
  std::snprintf(
      text, sizeof text,
      "point spacing %.2f mm as described (after any voxel filter) is %s than the %.2f-%.2f mm "
      "of this model's training scenes described alike (more than %gx): labels are unreliable; "
      "use a model for this sensor or a voxel size",
      point_spacing * 1e3, sparser ? "sparser" : "denser", low * 1e3, high * 1e3,
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

std::string units_hint(const TrainingSummary& training, const PointCloud& cloud,
                       const RunContext& context) {
  if (!(training.acquired_spacing_min > 0.0f) || cloud.empty()) return {};
  // The spacing as acquired (the figure the model's acquired range records), nothing more.
  const float spacing_in_units =
      median_point_spacing(cloud.xyz, NeighborSearch(cloud.xyz, context.stop), kUnitsSamples);
  // The median range from the sensor, over the same kind of strided sample.
  std::vector<float> ranges;
  const std::size_t stride = std::max<std::size_t>(1, cloud.size() / kUnitsSamples);
  for (std::size_t i = 0; i < cloud.size(); i += stride)
    if (is_finite(cloud.xyz[i])) ranges.push_back((cloud.xyz[i] - cloud.viewpoint.origin).norm());
  if (ranges.empty() || !(spacing_in_units > 0.0f)) return {};
  std::nth_element(ranges.begin(), ranges.begin() + std::ptrdiff_t(ranges.size() / 2),
                   ranges.end());
  const float range = ranges[ranges.size() / 2];
  struct Unit {
    float scale;
    const char *name, *flag;
  };
  for (const Unit& unit : {Unit{0.001f, "millimetres", "mm"}, Unit{0.01f, "centimetres", "cm"}}) {
    const float spacing = spacing_in_units * unit.scale;
    const float metres = range * unit.scale;
    if (spacing < training.acquired_spacing_min / kSpacingTolerance ||
        spacing > training.acquired_spacing_max * kSpacingTolerance || metres < kTableTopRangeMin ||
        metres > kTableTopRangeMax)
      continue;
    char text[240];
    std::snprintf(text, sizeof text,
                  "the cloud looks like %s (acquired spacing %.3g, median range %.4g in its "
                  "units): scale it by %g or pass --units %s",
                  unit.name, double(spacing_in_units), double(range), double(unit.scale),
                  unit.flag);
    return text;
  }
  return {};
}

}  // namespace primlabel::pipeline
