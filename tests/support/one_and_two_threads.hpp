#pragma once
// Results must not depend on the thread count: label_cloud on one thread and on two, to compare.

#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/labeling.hpp"

namespace primlabel::testing {

struct OneAndTwoThreads {
  pipeline::LabelingResult one, two;
};

// Labels two copies of `cloud` (label_cloud writes normals into its cloud), one thread first.
inline OneAndTwoThreads label_with_one_and_two_threads(const LabelModel& model,
                                                       const PointCloud& cloud,
                                                       const pipeline::LabelingOptions& options) {
  PointCloud for_one = cloud, for_two = cloud;
  // A braced list runs its elements in order.
  return {pipeline::label_cloud(model, for_one, options, RunContext{1}),
          pipeline::label_cloud(model, for_two, options, RunContext{2})};
}

}  // namespace primlabel::testing
