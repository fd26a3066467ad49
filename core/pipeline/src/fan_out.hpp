#pragma once
// The way back of label_cloud: the answers of the described cloud's slots carried to every input
// point through the plan.

#include "labeling_plan.hpp"
#include "primlabel/pipeline/crease_points.hpp"
#include "primlabel/pipeline/labeling.hpp"

namespace primlabel::pipeline {

// Turns `result`, one row per slot of `described`, into one row per point of `cloud`: labels
// (class 0 without a slot), probabilities and descriptors (NaN rows without one) and, unless the
// cloud's own normals were kept, the slots' normals and curvature written into `cloud`. When a
// slot stands for several points, labeled_points counts input points. `crease` (may be null): the
// points decided on their own near creases, whose labels and probabilities replace their slot's
// (crease_points.hpp). result.probabilities is emptied unless options.want_probabilities. Adds
// seconds.fanout.
void fan_out(const LabelingPlan& plan, const PointCloud& described, const LabelingOptions& options,
             PointCloud& cloud, LabelingResult& result, const CreaseAnswers* crease = nullptr);

}  // namespace primlabel::pipeline
