#pragma once
// What label_cloud makes of its options: the feature settings it describes with and the voxel
// size it downsamples to (validate, in labeling.hpp, refuses what it cannot honour).

#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/labeling.hpp"

namespace primlabel::pipeline {

// The model's feature settings with the request's radius overrides applied (a radius keeps the
// model's neighbour cap when the model already used a radius), without downsampling: label_cloud
// downsamples itself. Expects validated options.
FeatureSettings effective_features(const LabelModel& model, const LabelingOptions& options);

// The request's voxel size, else the model's own (0: every point).
float effective_voxel_size(const LabelModel& model, const LabelingOptions& options);

}  // namespace primlabel::pipeline
