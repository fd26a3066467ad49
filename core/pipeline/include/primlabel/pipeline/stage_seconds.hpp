#pragma once
// Where the time of one labeling went: wall seconds per stage, each second counted in exactly one
// stage, so the stages add up to label_cloud's time (less the bookkeeping between them). Logs,
// metrics and benchmarks name the stages from kLabelingStages, never field by field.

#include <array>

namespace primlabel::pipeline {

struct StageSeconds {
  double voxels = 0;       // voxel downsampling
  double tabletop = 0;     // table-top segmentation
  double duplicates = 0;   // the search for exact duplicates
  double index = 0;        // the neighbour index and the point-spacing measure
  double lists = 0;        // the radius search shared by normals, descriptors and graph
  double normals = 0;      // normal estimation (0 with the cloud's own normals)
  double cascade = 0;      // the plane cascade's split (LabelingOptions::plane_cascade)
  double descriptors = 0;  // FPFH / PFH
  double shapes = 0;       // shape evidence: the objects fitted with boxes and cylinders
  double graph = 0;        // the CRF's neighbourhood graph
  double inference = 0;    // CRF inference, or the SVM point by point
  double fanout = 0;       // carrying the described points' answers to every input point
  double primitives = 0;   // segmentation and fitting (only when asked)

  double total() const;
};

struct LabelingStage {
  const char* name;
  double StageSeconds::*seconds;
};

inline constexpr std::array<LabelingStage, 13> kLabelingStages = {{
    {"voxels", &StageSeconds::voxels},
    {"tabletop", &StageSeconds::tabletop},
    {"duplicates", &StageSeconds::duplicates},
    {"index", &StageSeconds::index},
    {"lists", &StageSeconds::lists},
    {"normals", &StageSeconds::normals},
    {"cascade", &StageSeconds::cascade},
    {"descriptors", &StageSeconds::descriptors},
    {"shapes", &StageSeconds::shapes},
    {"graph", &StageSeconds::graph},
    {"inference", &StageSeconds::inference},
    {"fanout", &StageSeconds::fanout},
    {"primitives", &StageSeconds::primitives},
}};

inline double StageSeconds::total() const {
  double sum = 0;
  for (const LabelingStage& stage : kLabelingStages) sum += this->*stage.seconds;
  return sum;
}

}  // namespace primlabel::pipeline
