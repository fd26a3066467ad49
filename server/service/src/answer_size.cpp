#include "primlabel/service/answer_size.hpp"

#include <algorithm>

#include "primlabel/tabletop/tabletop.hpp"
#include "primlabel/wire/packing.hpp"

namespace primlabel::service {

std::uint64_t array_bytes_per_point(const AnswerArrays& arrays) {
  return wire::kLabelBytesPerPoint + sizeof(float) * arrays.descriptor_dim +
         sizeof(float) * arrays.classes + (arrays.segments ? sizeof(std::uint32_t) : 0) +
         (arrays.objects ? sizeof(std::uint32_t) : 0);
}

std::uint64_t answer_bytes_per_point(const JobPlan& plan) {
  AnswerArrays arrays;
  arrays.segments = plan.options.want_primitives;
  arrays.objects = plan.options.want_objects;
  std::uint64_t bytes = array_bytes_per_point(arrays);
  // Until the choice is made, the largest answer any candidate would give.
  for (const ModelEntry* entry : plan.possible_models()) {
    const LabelModel& model = *entry->model;
    if (plan.options.want_descriptors)
      arrays.descriptor_dim = std::uint64_t(model.features.descriptor_dim());
    if (plan.options.want_probabilities) arrays.classes = model.class_ids().size();
    bytes = std::max(bytes, array_bytes_per_point(arrays));
  }
  if (plan.options.want_objects) {
    // Every object holds at least min_size points of the cloud (clusters smaller are dropped
    // and the refinements only split off parts at least as large).
    const std::uint64_t min_points =
        std::max<std::size_t>(1, tabletop::TabletopOptions{}.clusters.min_size);
    bytes += (kMaxObjectMessageBytes + min_points - 1) / min_points;
  }
  return bytes;
}

std::uint64_t answer_summary_bytes(const JobPlan& plan) {
  std::uint64_t bytes = 0;
  const std::uint64_t segments = plan.options.primitives.segments.max_segments;
  if (plan.options.want_primitives) bytes += segments * kMaxPrimitiveMessageBytes;
  // The table, and each segment's id listed by at most one object (5 bytes a varint).
  if (plan.options.want_objects)
    bytes += kMaxTableMessageBytes + (plan.options.want_primitives ? 5 * segments : 0);
  return bytes;
}

}  // namespace primlabel::service
