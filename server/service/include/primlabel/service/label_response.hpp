#pragma once
// The answer to a labeling request: LabelChunks of packed per-point arrays in input order, each
// under a byte budget so it fits any client's message limit, and the LabelSummary.

#include <cstdint>

#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/service/job_plan.hpp"
#include "primlabel/service/model_registry.hpp"
#include "primlabel/service/request_record.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::service {

class LabelResponder {
 public:
  // `requested_points` = LabelOptions.response_chunk_points (0 = as many as fit `max_bytes`).
  LabelResponder(const pipeline::LabelingResult& result, std::uint32_t requested_points,
                 std::uint64_t max_bytes);

  std::uint64_t chunk_points() const { return chunk_points_; }
  std::uint64_t chunk_count() const;
  // Chunk `index` (points [index * chunk_points, ...)).
  void fill_chunk(std::uint64_t index, v1::LabelChunk& chunk) const;
  // Points [first, first + count).
  void fill_range(std::uint64_t first, std::uint64_t count, v1::LabelChunk& chunk) const;

 private:
  const pipeline::LabelingResult& result_;
  std::uint64_t points_;
  std::uint64_t classes_;
  std::uint64_t chunk_points_;
};

// `plan.entry` is the model that labeled the cloud.
void fill_summary(const RequestRecord& record, const JobPlan& plan,
                  const pipeline::LabelingResult& result, v1::LabelSummary& summary);

}  // namespace primlabel::service
