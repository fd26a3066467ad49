// The plane cascade (LabelingOptions::plane_cascade): a model trained on a synthetic LMS400
// scene labels a held-out one with the cascade nearly as well as without it, while most points
// skip the descriptor and the CRF; the cascade stands aside wherever it cannot or must not run.

#include <gtest/gtest.h>

#include <cmath>

#include "primlabel/crf/metrics.hpp"
#include "primlabel/geometry/cloud_signature.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/synth/generate.hpp"
#include "training_scenes.hpp"

namespace primlabel {
namespace {

// A CRF (node weights trained on one training scene, a uniform coupling) and a held-out scene.
struct Trained {
  LabelModel model;
  PointCloud test_scene;
};

const Trained& trained() {
  static const Trained once = [] {
    const crf::GraphSettings graph;
    const FeatureSettings features;
    std::vector<PointCloud> scans = testing::lms400_scenes(synth::SceneSet::kTrain, 1);
    // What primlabel-train records of its scans: the noise bound of the cascade.
    const CloudSignature acquired = measure_signature(scans[0].xyz, scans[0].viewpoint.origin);
    auto scenes = testing::prepare_training_scenes(std::move(scans), {}, features, graph);
    scenes.train.front().acquired = acquired;
    pipeline::ModelTrainingOptions options;
    options.kind = ModelKind::kNodeOnly;
    options.iterations = 60;
    LabelModel model = testing::train_on(scenes, features, graph, options).model;
    model.kind = ModelKind::kCrf;
    crf::CrfModel& w = model.weights;
    w.edge_weights = Eigen::MatrixXf::Zero(w.num_classes(), w.edge_feature_dim());
    w.edge_weights.col(w.edge_feature_dim() - 1).setConstant(0.25f);
    return Trained{std::move(model),
                   synth::synthetic_scene(synth::SceneSet::kTest, 0, synth::SensorKind::kLms400)};
  }();
  return once;
}

double accuracy(const LabelModel& model, const PointCloud& truth,
                const std::vector<std::uint32_t>& predicted) {
  crf::ConfusionMatrix confusion(model.class_ids());
  confusion.add(truth.labels, predicted, 0u);
  return confusion.accuracy();
}

pipeline::LabelingResult label(const LabelModel& model, PointCloud cloud,
                               pipeline::LabelingOptions options, int threads = 2) {
  return pipeline::label_cloud(model, cloud, options, RunContext{threads});
}

TEST(PlaneCascade, MostPointsSkipTheCrfAndTheAccuracyHolds) {
  const Trained& t = trained();
  ASSERT_GT(t.model.training.roughness_max, 0.0f);
  pipeline::LabelingOptions options;
  const pipeline::LabelingResult exact = label(t.model, t.test_scene, options);
  options.plane_cascade = true;
  options.want_probabilities = true;
  const pipeline::LabelingResult cascaded = label(t.model, t.test_scene, options);
  EXPECT_EQ(exact.cascaded_points, 0u);
  // A table scene is mostly plane: a large share of its points are the cascade's.
  EXPECT_GT(cascaded.cascaded_points, cascaded.described_points * 3 / 10);
  EXPECT_EQ(cascaded.labeled_points, exact.labeled_points);
  EXPECT_GT(cascaded.seconds.cascade, 0.0);
  const double with = accuracy(t.model, t.test_scene, cascaded.labels);
  const double without = accuracy(t.model, t.test_scene, exact.labels);
  EXPECT_GT(with, without - 0.005) << "with " << with << ", without " << without;
  // Every labeled point has a probability row that sums to 1, the cascade's included.
  for (Eigen::Index i = 0; i < cascaded.probabilities.rows(); ++i) {
    if (cascaded.labels[std::size_t(i)] == class_id(PrimitiveClass::kUnknown)) continue;
    ASSERT_NEAR(cascaded.probabilities.row(i).sum(), 1.0f, 1e-4f) << "point " << i;
  }
  // The same labels whatever the threads.
  options.want_probabilities = false;
  EXPECT_EQ(label(t.model, t.test_scene, options, 1).labels, cascaded.labels);
}

TEST(PlaneCascade, StandsAsideWhenEveryPointMustBeDescribedOrNoNoiseIsKnown) {
  const Trained& t = trained();
  pipeline::LabelingOptions exact_options;
  const pipeline::LabelingResult exact = label(t.model, t.test_scene, exact_options);
  pipeline::LabelingOptions options;
  options.plane_cascade = true;
  options.want_descriptors = true;  // every point's descriptor asked for
  const pipeline::LabelingResult described = label(t.model, t.test_scene, options);
  EXPECT_EQ(described.cascaded_points, 0u);
  EXPECT_EQ(described.labels, exact.labels);

  LabelModel unrecorded = t.model;  // trained before the noise was recorded
  unrecorded.training.surface_variation_max = 0.0f;
  unrecorded.training.roughness_max = 0.0f;
  options.want_descriptors = false;
  const pipeline::LabelingResult old = label(unrecorded, t.test_scene, options);
  EXPECT_EQ(old.cascaded_points, 0u);
  EXPECT_EQ(old.labels, exact.labels);
}

}  // namespace
}  // namespace primlabel
