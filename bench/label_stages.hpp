#pragma once
// The stages of label_cloud in ms, in pipeline order (voxel and table-top make up prefilter),
// as the pipeline and server benchmarks print them.

#include "primlabel/pipeline/labeling.hpp"

namespace primlabel::bench {

struct LabelStage {
  const char* name;
  double (*ms)(const pipeline::LabelingResult&);
};

inline constexpr LabelStage kLabelStages[] = {
    {"voxel", [](const pipeline::LabelingResult& r) { return 1e3 * r.voxel_seconds; }},
    {"index", [](const pipeline::LabelingResult& r) { return 1e3 * r.index_seconds; }},
    {"lists", [](const pipeline::LabelingResult& r) { return 1e3 * r.lists_seconds; }},
    {"normals", [](const pipeline::LabelingResult& r) { return 1e3 * r.normal_seconds; }},
    {"fpfh", [](const pipeline::LabelingResult& r) { return 1e3 * r.descriptor_seconds; }},
    {"graph", [](const pipeline::LabelingResult& r) { return 1e3 * r.graph_seconds; }},
    {"infer",
     [](const pipeline::LabelingResult& r) {
       return 1e3 * (r.inference_seconds - r.graph_seconds);  // inference_seconds holds the graph
     }},
    {"fanout", [](const pipeline::LabelingResult& r) { return 1e3 * r.fanout_seconds; }},
};

}  // namespace primlabel::bench
