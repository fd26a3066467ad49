#pragma once
// The stages of a labeling request, named once: the log line's <stage>_ms keys, the
// primlabel_stage_seconds{stage=...} series and the response's StageTiming entries all come from
// kStages, in pipeline order.

#include <array>

namespace primlabel::ops {

// Seconds per stage; negative = the stage did not run.
struct StageTimes {
  double receive = -1, prefilter = -1, normals = -1, features = -1, inference = -1, primitives = -1,
         send = -1;
};

struct StageField {
  const char* name;
  double StageTimes::*seconds;
};

inline constexpr std::array<StageField, 7> kStages = {{
    {"receive", &StageTimes::receive},
    {"prefilter", &StageTimes::prefilter},
    {"normals", &StageTimes::normals},
    {"features", &StageTimes::features},
    {"inference", &StageTimes::inference},
    {"primitives", &StageTimes::primitives},  // only with return_primitives
    {"send", &StageTimes::send},
}};

}  // namespace primlabel::ops
