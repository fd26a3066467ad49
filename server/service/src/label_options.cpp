#include "primlabel/service/label_options.hpp"

#include <string>

namespace primlabel::service {

pipeline::LabelingOptions labeling_options(const v1::ScanHeader& header) {
  const v1::LabelOptions& options = header.options();
  pipeline::LabelingOptions labeling;
  labeling.want_descriptors = options.return_descriptors();
  labeling.want_probabilities = options.return_probabilities();
  labeling.tabletop_only = options.tabletop_only();
  labeling.voxel_size = options.voxel_size();
  labeling.normal_radius = options.normal_radius();
  labeling.feature_radius = options.feature_radius();
  labeling.use_cloud_normals = header.layout().normals();
  labeling.want_primitives = options.return_primitives();
  labeling.want_objects = options.return_objects();
  // The plane cascade by default; the pipeline stands it aside where it cannot apply (descriptors
  // asked for, the client's own normals, models that recorded no training noise or have no
  // plane class).
  labeling.plane_cascade = !options.every_point();
  return labeling;
}

namespace {

// The refusal in the request's terms: the v1::LabelOptions fields, and which model.
ServiceError in_request_terms(const pipeline::OptionsRefusal& refusal, const ModelEntry* model,
                              bool chosen) {
  using pipeline::RefusedOption;
  switch (refusal.option) {
    case RefusedOption::kVoxelSize:
      return {ErrorCode::kInvalidArgument, "options.voxel_size must be finite and >= 0"};
    case RefusedOption::kRadius:
      return {ErrorCode::kInvalidArgument,
              "options.normal_radius and options.feature_radius must be finite and >= 0"};
    case RefusedOption::kObjects:
      return {ErrorCode::kInvalidArgument,
              "options.return_objects needs options.tabletop_only (the objects are those of the "
              "table-top stage)"};
    case RefusedOption::kRadiusOverride:
      if (model)
        return {ErrorCode::kInvalidArgument,
                "model '" + model->name + "' version '" + model->version +
                    "' does not allow radius overrides (options.normal_radius / feature_radius)" +
                    (chosen ? "" : "; name a model that does")};
      break;
    case RefusedOption::kPrimitives:
      break;
  }
  return {ErrorCode::kInvalidArgument, "options: " + refusal.reason};
}

}  // namespace

std::optional<ServiceError> refuse_options(const pipeline::LabelingOptions& options) {
  if (auto refused = pipeline::refusal(options)) return in_request_terms(*refused, nullptr, false);
  return std::nullopt;
}

std::optional<ServiceError> refuse_options(const pipeline::LabelingOptions& options,
                                           const ModelEntry& model, bool chosen) {
  if (auto refused = pipeline::refusal(*model.model, options))
    return in_request_terms(*refused, &model, chosen);
  return std::nullopt;
}

}  // namespace primlabel::service
