#include "labeling_options.hpp"

#include <cmath>
#include <stdexcept>

namespace primlabel::pipeline {

void validate(const LabelModel& model, const LabelingOptions& options) {
  if (!(options.voxel_size >= 0.0f) || !std::isfinite(options.voxel_size))
    throw std::invalid_argument("voxel size must be finite and >= 0");
  if (options.want_primitives) options.primitives.validate();
  if (options.want_objects && !options.tabletop_only)
    throw std::invalid_argument("objects need the table-top stage (tabletop_only)");
  const bool overrides = options.normal_radius > 0.0f || options.feature_radius > 0.0f;
  if (overrides && !model.features.radii_overridable)
    throw std::invalid_argument("model '" + model.name + "' does not allow radius overrides");
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
