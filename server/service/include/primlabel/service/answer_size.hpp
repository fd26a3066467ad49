#pragma once
// The size of a labeling answer, in one place: the packed arrays every point carries
// (LabelChunk), what the plan's answer may take before labeling (the session's memory check)
// and bounds on the summary's messages.

#include <cstdint>

#include "primlabel/service/job_plan.hpp"

namespace primlabel::service {

// The answer's per-point arrays: a label, and as asked the descriptor, the class
// probabilities, a segment id (primitives) and an object id (objects).
struct AnswerArrays {
  std::uint64_t descriptor_dim = 0;  // 0: no descriptors
  std::uint64_t classes = 0;         // 0: no probabilities
  bool segments = false;
  bool objects = false;
};
std::uint64_t array_bytes_per_point(const AnswerArrays& arrays);

// Bytes per point of the answer the plan asks for (the arrays, and the objects' messages per
// point), known before labeling: until the model is chosen, the largest any candidate gives.
std::uint64_t answer_bytes_per_point(const JobPlan& plan);

// A bound on one encoded v1::Primitive (a plane, the largest: 16 doubles and 4 scalars with their
// tags, about 300 bytes); test_service_primitives checks real messages against it.
inline constexpr std::uint64_t kMaxPrimitiveMessageBytes = 400;
// A bound on one encoded v1::TabletopObject without its primitive ids (an id, a count, three
// Vec3d and a double with their tags: about 110 bytes).
inline constexpr std::uint64_t kMaxObjectMessageBytes = 160;
// An estimate of the encoded v1::TabletopTable: the plane and up to 1024 hull vertices at 31 bytes
// each (the hull of the table's grid cells has far fewer).
inline constexpr std::uint64_t kMaxTableMessageBytes = 64 + 1024 * 31;
// Bytes the summary may carry on top of its fixed part, whatever the cloud size: the primitives
// (at most PrimitiveOptions::segments.max_segments of them) and the table with the objects'
// primitive ids (the objects themselves are counted per point in answer_bytes_per_point).
std::uint64_t answer_summary_bytes(const JobPlan& plan);

}  // namespace primlabel::service
