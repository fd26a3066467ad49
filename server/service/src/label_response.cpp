#include "primlabel/service/label_response.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/ops/stage_times.hpp"
#include "primlabel/service/answer_size.hpp"
#include "primlabel/service/object_messages.hpp"
#include "primlabel/service/primitive_messages.hpp"
#include "primlabel/wire/packing.hpp"

namespace primlabel::service {

LabelResponder::LabelResponder(const pipeline::LabelingResult& result,
                               std::uint32_t requested_points, std::uint64_t max_bytes)
    : result_(result),
      points_(result.labels.size()),
      classes_(std::uint64_t(result.probabilities.cols())) {
  const std::uint64_t bytes_per_point =
      array_bytes_per_point({result.descriptors.empty() ? 0 : std::uint64_t(result.descriptors.dim),
                             classes_, bool(result.primitives), bool(result.objects)});
  const std::uint64_t fitting = std::max<std::uint64_t>(1, max_bytes / bytes_per_point);
  chunk_points_ =
      requested_points > 0 ? std::min<std::uint64_t>(requested_points, fitting) : fitting;
}

std::uint64_t LabelResponder::chunk_count() const {
  return (points_ + chunk_points_ - 1) / chunk_points_;
}

void LabelResponder::fill_chunk(std::uint64_t index, v1::LabelChunk& chunk) const {
  const std::uint64_t first = index * chunk_points_;
  fill_range(first, std::min(chunk_points_, points_ - first), chunk);
}

void LabelResponder::fill_range(std::uint64_t first, std::uint64_t count,
                                v1::LabelChunk& chunk) const {
  chunk.set_first_point(first);
  chunk.set_point_count(static_cast<std::uint32_t>(count));
  wire::append_le(*chunk.mutable_labels(),
                  std::span<const std::uint32_t>(result_.labels.data() + first, count));
  if (!result_.descriptors.empty()) {
    const std::size_t d = std::size_t(result_.descriptors.dim);
    wire::append_le(*chunk.mutable_descriptors(),
                    std::span<const float>(result_.descriptors.row(first).data(), count * d));
  }
  if (classes_ > 0) {
    // Eigen is column-major: gather each point's row.
    std::vector<float> rows(count * classes_);
    for (std::uint64_t i = 0; i < count; ++i)
      for (std::uint64_t k = 0; k < classes_; ++k)
        rows[i * classes_ + k] = result_.probabilities(Eigen::Index(first + i), Eigen::Index(k));
    wire::append_le(*chunk.mutable_probabilities(), std::span<const float>(rows));
  }
  if (result_.primitives)
    wire::append_le(
        *chunk.mutable_segments(),
        std::span<const std::uint32_t>(result_.primitives->point_segment.data() + first, count));
  if (result_.objects)
    wire::append_le(
        *chunk.mutable_objects(),
        std::span<const std::uint32_t>(result_.objects->point_object.data() + first, count));
}

namespace {

// The model's own name for a class, else the taxonomy's.
std::string class_name_of(const ModelEntry& entry, std::uint32_t id) {
  for (const v1::PrimitiveClass& c : entry.metadata.classes())
    if (c.id() == id) return c.name();
  const auto taxonomy_class = class_from_id(id);
  return taxonomy_class ? std::string(name(*taxonomy_class)) : std::string();
}

v1::ModelChoice choice_message(pipeline::ChoiceReason reason) {
  switch (reason) {
    case pipeline::ChoiceReason::kNamed:
      return v1::MODEL_CHOICE_NAMED;
    case pipeline::ChoiceReason::kDomain:
      return v1::MODEL_CHOICE_DOMAIN;
    case pipeline::ChoiceReason::kDefault:
      return v1::MODEL_CHOICE_DEFAULT;
  }
  return v1::MODEL_CHOICE_UNSPECIFIED;
}

}  // namespace

void fill_summary(const RequestRecord& record, const JobPlan& plan,
                  const pipeline::LabelingResult& result, v1::LabelSummary& summary) {
  const ModelEntry& entry = *plan.entry;
  summary.set_model_choice(choice_message(plan.choice));
  summary.set_model_choice_reason(plan.choice_why);
  summary.set_request_id(record.id());
  summary.set_scan_id(record.scan_id);
  summary.set_frame_id(record.frame_id);
  summary.set_stamp_ns(record.stamp_ns);
  summary.set_model(entry.name);
  summary.set_model_version(entry.version);
  summary.set_points_received(record.points);
  summary.set_points_dropped_non_finite(record.dropped_non_finite);

  std::map<std::uint32_t, std::uint64_t> counts;
  for (std::uint32_t id : result.class_ids) counts[id] = 0;
  // Class ids are small: count in a flat table (a map lookup per point cost ms on a frame).
  constexpr std::uint32_t kDenseIds = 256;
  std::vector<std::uint64_t> dense(kDenseIds, 0);
  for (std::uint32_t label : result.labels) {
    if (label < kDenseIds)
      ++dense[label];
    else
      ++counts[label];
  }
  for (std::uint32_t id = 0; id < kDenseIds; ++id)
    if (dense[id] > 0) counts[id] += dense[id];
  const std::uint32_t unknown = class_id(PrimitiveClass::kUnknown);
  const auto unlabeled = counts.find(unknown);
  const std::uint64_t labeled =
      result.labels.size() - (unlabeled == counts.end() ? 0 : unlabeled->second);
  summary.set_points_labeled(labeled);
  for (const auto& [id, points] : counts) {
    v1::ClassCount* count = summary.add_class_counts();
    count->set_class_id(id);
    count->set_points(points);
    count->set_name(class_name_of(entry, id));
  }
  for (const auto& [name, field] : ops::kStages) {
    const double seconds = record.stages.*field;
    if (seconds < 0) continue;
    v1::StageTiming* timing = summary.add_timings();
    timing->set_stage(name);
    timing->set_seconds(seconds);
  }
  summary.set_descriptor_dim(static_cast<std::uint32_t>(result.descriptors.dim));
  if (entry.model) summary.set_descriptor_name(entry.model->features.descriptor_name());
  summary.set_cascaded_points(result.cascaded_points);
  summary.set_points_isolated(result.isolated_points);
  if (std::isfinite(result.point_spacing)) summary.set_point_spacing(result.point_spacing);
  summary.set_domain_warning(result.domain_warning);
  *summary.mutable_classes() = entry.metadata.classes();
  if (result.primitives) add_primitives(result.primitives->primitives, summary);
  if (result.objects) add_objects(*result.objects, summary);
}

}  // namespace primlabel::service
