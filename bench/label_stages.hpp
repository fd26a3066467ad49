#pragma once
// label_cloud's stages in ms, as the pipeline and server benchmarks print them: the names and the
// order are pipeline::kLabelingStages', a column as wide as its name.

#include <algorithm>
#include <cstring>

#include "primlabel/pipeline/stage_seconds.hpp"

namespace primlabel::bench {

inline double stage_ms(const pipeline::StageSeconds& seconds,
                       const pipeline::LabelingStage& stage) {
  return 1e3 * (seconds.*stage.seconds);
}

inline int stage_column_width(const pipeline::LabelingStage& stage) {
  return std::max(7, static_cast<int>(std::strlen(stage.name)));
}

}  // namespace primlabel::bench
