// Labeling a cloud with a trained model: describe with the model's settings, build its graph,
// infer (CRF or node-only) or classify point by point (SVM), optionally restricted to the
// table-top.

#include <chrono>
#include <cmath>
#include <limits>

#include "primlabel/core/taxonomy.hpp"
#include "primlabel/crf/inference.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/svm_model.hpp"
#include "primlabel/tabletop/tabletop.hpp"

namespace primlabel::pipeline {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

LabelingResult label_all_points(const LabelModel& model, PointCloud& cloud,
                                const LabelingOptions& options) {
  LabelingResult result;
  result.class_ids = model.class_ids();
  DescribedCloud described = describe_cloud(cloud, model.features, options.threads);
  result.feature_seconds = described.normal_seconds + described.feature_seconds;
  if (model.kind == ModelKind::kSvm) {  // point by point: no graph
    LabelingResult svm = label_described_with_svm(model, described, options);
    svm.feature_seconds = result.feature_seconds;
    return svm;
  }

  const auto start = std::chrono::steady_clock::now();
  crf::GraphOptions graph_options = model.graph;
  graph_options.threads = options.threads;
  // A node-only model ignores edges, so its graph needs none (only the active mask).
  if (model.kind == ModelKind::kNodeOnly) graph_options.neighborhood = Neighborhood::Knn(1);
  const crf::Graph graph = build_scene_graph(cloud, described, graph_options);
  crf::InferenceOptions inference = model.inference;
  inference.threads = options.threads;
  inference.unknown_label = class_id(PrimitiveClass::kUnknown);
  inference.compute_marginals = options.want_probabilities;
  crf::InferenceResult inferred = infer(model.weights, described.descriptors, graph, inference);
  result.inference_seconds = seconds_since(start);

  result.labels = std::move(inferred.labels);
  if (options.want_probabilities) result.probabilities = std::move(inferred.marginals);
  result.labeled_points = graph.num_active();
  return result;
}

}  // namespace

LabelingResult label_cloud(const LabelModel& model, PointCloud& cloud,
                           const LabelingOptions& options) {
  if (!options.tabletop_only) return label_all_points(model, cloud, options);

  // Table-top only: label the sub-cloud of table and object points, scatter back.
  tabletop::TabletopOptions tabletop_options;
  tabletop_options.threads = options.threads;
  const tabletop::TabletopResult segmented = tabletop::segment_tabletop(cloud, tabletop_options);
  const std::vector<std::uint8_t> mask = tabletop::tabletop_mask(segmented, cloud.size());
  PointCloud sub;
  std::vector<std::size_t> source_index;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (mask[i]) source_index.push_back(i);
  sub.resize_unorganized(source_index.size());
  sub.viewpoint = cloud.viewpoint;
  for (std::size_t j = 0; j < source_index.size(); ++j) sub.xyz[j] = cloud.xyz[source_index[j]];

  LabelingResult partial = label_all_points(model, sub, options);
  LabelingResult result;
  result.class_ids = partial.class_ids;
  result.labeled_points = partial.labeled_points;
  result.feature_seconds = partial.feature_seconds;
  result.inference_seconds = partial.inference_seconds;
  result.labels.assign(cloud.size(), class_id(PrimitiveClass::kUnknown));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.normals.assign(cloud.size(), Vec3f::Constant(nan));
  cloud.curvature.assign(cloud.size(), nan);
  if (options.want_probabilities)
    result.probabilities = Eigen::MatrixXf::Constant(Eigen::Index(cloud.size()),
                                                     Eigen::Index(result.class_ids.size()), nan);
  for (std::size_t j = 0; j < source_index.size(); ++j) {
    const std::size_t i = source_index[j];
    result.labels[i] = partial.labels[j];
    cloud.normals[i] = sub.normals[j];
    cloud.curvature[i] = sub.curvature[j];
    if (options.want_probabilities)
      result.probabilities.row(Eigen::Index(i)) = partial.probabilities.row(Eigen::Index(j));
  }
  return result;
}

}  // namespace primlabel::pipeline
