#include "labeling_options.hpp"

#include <cmath>
#include <stdexcept>

namespace primlabel::pipeline {

namespace {

bool finite_non_negative(float value) { return value >= 0.0f && std::isfinite(value); }

}  // namespace

std::optional<OptionsRefusal> refusal(const LabelingOptions& options) {
  if (!finite_non_negative(options.voxel_size))
    return OptionsRefusal{RefusedOption::kVoxelSize, "voxel_size must be finite and >= 0"};
  if (!finite_non_negative(options.normal_radius) || !finite_non_negative(options.feature_radius))
    return OptionsRefusal{RefusedOption::kRadius,
                          "normal_radius and feature_radius must be finite and >= 0"};
  if (options.want_primitives) {
    try {
      options.primitives.validate();
    } catch (const std::invalid_argument& e) {
      return OptionsRefusal{RefusedOption::kPrimitives, e.what()};
    }
  }
  if (options.want_objects && !options.tabletop_only)
    return OptionsRefusal{RefusedOption::kObjects,
                          "objects need the table-top stage (tabletop_only)"};
  return std::nullopt;
}

std::optional<OptionsRefusal> refusal(const LabelModel& model, const LabelingOptions& options) {
  if (auto refused = refusal(options)) return refused;
  const bool overrides = options.normal_radius > 0.0f || options.feature_radius > 0.0f;
  if (overrides && !model.features.radii_overridable)
    return OptionsRefusal{RefusedOption::kRadiusOverride,
                          "model '" + model.name + "' does not allow radius overrides"};
  return std::nullopt;
}

void validate(const LabelingOptions& options) {
  if (auto refused = refusal(options)) throw std::invalid_argument(refused->reason);
}

void validate(const LabelModel& model, const LabelingOptions& options) {
  if (auto refused = refusal(model, options)) throw std::invalid_argument(refused->reason);
}

FeatureSettings effective_features(const LabelModel& model, const LabelingOptions& options) {
  FeatureSettings settings = model.features;
  settings.voxel_size = 0.0f;
  auto override_radius = [](Neighborhood& neighborhood, float radius) {
    if (!(radius > 0.0f)) return;
    const int cap = neighborhood.radius > 0.0f ? neighborhood.max_neighbors : 0;
    neighborhood = Neighborhood{radius, 0, cap};
  };
  override_radius(settings.normals, options.normal_radius);
  override_radius(settings.features, options.feature_radius);
  return settings;
}

float effective_voxel_size(const LabelModel& model, const LabelingOptions& options) {
  return options.voxel_size > 0.0f ? options.voxel_size : model.features.voxel_size;
}

}  // namespace primlabel::pipeline
