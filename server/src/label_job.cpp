#include "label_job.hpp"

#include <algorithm>
#include <new>
#include <stdexcept>

#include "primlabel/tabletop/tabletop.hpp"
#include "registry_error.hpp"

namespace primlabel::server {

std::optional<ServiceError> plan_labeling(const v1::ScanHeader& header, ModelRegistry& registry,
                                          LabelPlan& plan) {
  try {
    plan.entry = registry.resolve(header.model(), header.model_version());
  } catch (const RegistryError& error) {
    return registry_error(error);
  }
  const LabelModel& model = *plan.entry->model;
  const std::string which =
      "model '" + plan.entry->name + "' version '" + plan.entry->version + "'";
  const v1::LabelOptions& options = header.options();
  if ((options.normal_radius() > 0.0f || options.feature_radius() > 0.0f) &&
      !model.features.radii_overridable)
    return ServiceError{
        ErrorCode::kInvalidArgument,
        which + " does not allow radius overrides (options.normal_radius / feature_radius)"};
  if (options.return_objects() && !options.tabletop_only())
    return ServiceError{ErrorCode::kInvalidArgument,
                        "options.return_objects needs options.tabletop_only (the objects are "
                        "those of the table-top stage)"};
  plan.options.want_descriptors = options.return_descriptors();
  plan.options.want_probabilities = options.return_probabilities();
  plan.options.tabletop_only = options.tabletop_only();
  plan.options.voxel_size = options.voxel_size();
  plan.options.normal_radius = options.normal_radius();
  plan.options.feature_radius = options.feature_radius();
  plan.options.use_cloud_normals = header.layout().normals();
  plan.options.want_primitives = options.return_primitives();
  plan.options.want_objects = options.return_objects();
  return std::nullopt;
}

std::uint64_t answer_bytes_per_point(const LabelPlan& plan) {
  const LabelModel& model = *plan.entry->model;
  std::uint64_t bytes = sizeof(std::uint32_t);
  if (plan.options.want_descriptors)
    bytes += sizeof(float) * std::uint64_t(model.features.descriptor_dim());
  if (plan.options.want_probabilities) bytes += sizeof(float) * model.class_ids().size();
  if (plan.options.want_primitives) bytes += sizeof(std::uint32_t);  // LabelChunk.segments
  if (plan.options.want_objects) {
    bytes += sizeof(std::uint32_t);  // LabelChunk.objects
    // Every object holds at least min_size points of the cloud (clusters smaller are dropped
    // and the refinements only split off parts at least as large).
    const std::uint64_t min_points =
        std::max<std::size_t>(1, tabletop::TabletopOptions{}.clusters.min_size);
    bytes += (kMaxObjectMessageBytes + min_points - 1) / min_points;
  }
  return bytes;
}

std::uint64_t answer_summary_bytes(const LabelPlan& plan) {
  std::uint64_t bytes = 0;
  const std::uint64_t segments = plan.options.primitives.segments.max_segments;
  if (plan.options.want_primitives) bytes += segments * kMaxPrimitiveMessageBytes;
  // The table, and each segment's id listed by at most one object (5 bytes a varint).
  if (plan.options.want_objects)
    bytes += kMaxTableMessageBytes + (plan.options.want_primitives ? 5 * segments : 0);
  return bytes;
}

std::optional<ServiceError> run_label_job(const LabelPlan& plan, PointCloud& cloud,
                                          const RunContext& context,
                                          pipeline::LabelingResult& result) {
  try {
    result = pipeline::label_cloud(*plan.entry->model, cloud, plan.options, context);
    return std::nullopt;
  } catch (const pipeline::Cancelled&) {
    return ServiceError{ErrorCode::kCancelled, "labeling was cancelled"};
  } catch (const std::invalid_argument& e) {
    return ServiceError{ErrorCode::kInvalidArgument, e.what()};
  } catch (const std::bad_alloc&) {
    return ServiceError{ErrorCode::kResourceExhausted, "out of memory while labeling"};
  } catch (const std::exception& e) {
    return ServiceError{ErrorCode::kInternal, std::string("labeling failed: ") + e.what()};
  } catch (...) {
    return ServiceError{ErrorCode::kInternal, "labeling failed: an unknown exception"};
  }
}

ServiceError server_busy(const Admission& admission) {
  return {ErrorCode::kResourceExhausted,
          "the server is busy: " + std::to_string(admission.admitted()) + " requests labeling (" +
              std::to_string(admission.workers()) + " workers, " +
              std::to_string(admission.capacity() - admission.workers()) +
              " queued at most; --workers, --queue); retry later"};
}

ServiceError shutting_down() { return {ErrorCode::kUnavailable, "the server is shutting down"}; }

}  // namespace primlabel::server
