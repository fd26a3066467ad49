#pragma once
// The way back of label_cloud: the answers of the described cloud's slots carried to every input
// point through the plan.

#include "labeling_plan.hpp"
#include "primlabel/pipeline/labeling.hpp"

namespace primlabel::pipeline {

// Turns `result`, one row per slot of `described`, into one row per point of `cloud`: labels
// (class 0 without a slot), probabilities and descriptors (NaN rows without one) and, unless the
// cloud's own normals were kept, the slots' normals and curvature written into `cloud`. When a
// slot stands for several points, labeled_points counts input points. Adds seconds.fanout.
void fan_out(const LabelingPlan& plan, const PointCloud& described, const LabelingOptions& options,
             PointCloud& cloud, LabelingResult& result);

}  // namespace primlabel::pipeline
