// label_cloud end to end: a model trained on two synthetic LMS400 training scenes labels a
// held-out test scene far better than chance, the same for 1 and 2 threads, and survives a
// round trip through its file.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <random>

#include "crf_scenes.hpp"
#include "one_and_two_threads.hpp"
#include "primlabel/crf/metrics.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/synth/generate.hpp"
#include "random_label_model.hpp"
#include "training_scenes.hpp"

namespace primlabel {
namespace {

using pipeline::SceneData;

// A node-only model trained on two training scenes, and a held-out test scene.
struct Trained {
  LabelModel model;
  PointCloud test_scene;
};

Trained train_on_two_scenes() {
  const crf::GraphSettings graph;
  const FeatureSettings features;
  const auto scenes = testing::prepare_training_scenes(
      testing::lms400_scenes(synth::SceneSet::kTrain, 2), {}, features, graph);
  pipeline::ModelTrainingOptions options;
  options.kind = ModelKind::kNodeOnly;
  options.iterations = 100;
  return {testing::train_on(scenes, features, graph, options).model,
          synth::synthetic_scene(synth::SceneSet::kTest, 0, synth::SensorKind::kLms400)};
}

double accuracy(const LabelModel& model, const PointCloud& truth,
                const std::vector<std::uint32_t>& predicted) {
  crf::ConfusionMatrix confusion(model.class_ids());
  confusion.add(truth.labels, predicted, 0u);
  return confusion.accuracy();
}

// A CRF: the node-only weights plus an associative coupling between neighbours.
LabelModel with_coupling(LabelModel model, float coupling) {
  model.kind = ModelKind::kCrf;
  crf::CrfModel& w = model.weights;
  w.edge_weights = Eigen::MatrixXf::Zero(w.num_classes(), w.edge_feature_dim());
  w.edge_weights.col(w.edge_feature_dim() - 1).setConstant(coupling);
  return model;
}

// Untrained: all-zero weights over three classes (labels every described point "plane").

PointCloud small_scene() {
  PointCloud scene = synth::synthetic_scene(synth::SceneSet::kTest, 1, synth::SensorKind::kLms400);
  return scene;
}

double majority_fraction(const PointCloud& cloud) {
  std::vector<std::size_t> counts(kPrimitiveClassCount, 0);
  std::size_t total = 0;
  for (std::uint32_t id : cloud.labels)
    if (id != 0) ++counts[id], ++total;
  return double(*std::max_element(counts.begin(), counts.end())) / double(total);
}

// One case, so the training runs once per process (ctest runs each case in its own process).
TEST(PipelineLabeling, TrainedModelLabelsHeldOutSceneDeterministicallyAndAfterRoundTrip) {
  const Trained trained = train_on_two_scenes();
  const LabelModel& model = trained.model;
  // Trained with the default tent node basis, so its sparse scoring path is what runs below.
  ASSERT_EQ(model.weights.node_knots, crf::default_node_knots());

  // Node-only, with probabilities: far above chance (the majority class, the table, ~60%).
  PointCloud cloud = trained.test_scene;
  pipeline::LabelingOptions options;
  options.want_probabilities = true;
  const auto result = pipeline::label_cloud(model, cloud, options, RunContext{2});
  ASSERT_EQ(result.labels.size(), cloud.size());
  // The training scenes' spacing is recorded; a held-out scene of the same sensor is inside it,
  // the same scene four times larger or smaller is not.
  EXPECT_GT(model.training.point_spacing_min, 0.0f);
  EXPECT_GE(model.training.point_spacing_max, model.training.point_spacing_min);
  EXPECT_LT(model.training.point_spacing_max, 0.01f);
  EXPECT_GT(model.training.surface_variation_max, 0.0f);
  EXPECT_EQ(result.domain_warning, "");
  EXPECT_GT(result.point_spacing, model.training.point_spacing_min / 2);
  EXPECT_LT(result.point_spacing, model.training.point_spacing_max * 2);
  for (float scale : {4.0f, 0.25f}) {
    PointCloud scaled = trained.test_scene;
    for (Vec3f& p : scaled.xyz) p *= scale;
    const auto far = pipeline::label_cloud(model, scaled, {}, RunContext{2});
    EXPECT_NEAR(far.point_spacing, result.point_spacing * scale,
                result.point_spacing * scale * 0.01f);
    EXPECT_NE(far.domain_warning.find(scale > 1 ? "sparser" : "denser"), std::string::npos)
        << scale << ": " << far.domain_warning;
  }
  {  // 4 mm of range noise, far above the scanner's: the warning names the noise
    PointCloud noisy = trained.test_scene;
    std::mt19937 rng(5);
    std::normal_distribution<float> noise(0.0f, 0.004f);
    for (Vec3f& p : noisy.xyz) p.z() += noise(rng);
    const auto warned = pipeline::label_cloud(model, noisy, {}, RunContext{2});
    EXPECT_NE(warned.domain_warning.find("surface variation"), std::string::npos)
        << warned.domain_warning << " (" << warned.surface_variation << " vs "
        << model.training.surface_variation_max << ")";
  }
  const double node_accuracy = accuracy(model, trained.test_scene, result.labels);
  EXPECT_GT(node_accuracy, 0.80);
  EXPECT_GT(node_accuracy, majority_fraction(trained.test_scene) + 0.15);
  ASSERT_EQ(result.probabilities.rows(), Eigen::Index(cloud.size()));
  ASSERT_EQ(result.probabilities.cols(), Eigen::Index(model.class_ids().size()));
  for (Eigen::Index i = 0; i < result.probabilities.rows(); i += 997)
    if (result.probabilities.row(i).allFinite())
      EXPECT_NEAR(result.probabilities.row(i).sum(), 1.0f, 1e-4f);

  // CRF: same labels for 1 and 2 threads.
  const LabelModel crf = with_coupling(model, 0.5f);
  options = {};
  const auto [with_one, with_two] =
      testing::label_with_one_and_two_threads(crf, trained.test_scene, options);
  EXPECT_EQ(with_one.labels, with_two.labels);
  EXPECT_GT(accuracy(crf, trained.test_scene, with_two.labels), 0.80);

  // The model file round trip labels the same.
  const auto path = std::filesystem::temp_directory_path() /
                    ("primlabel_pipeline_model_" + std::to_string(::getpid()) + ".plm");
  save_model(path.string(), crf);
  const LabelModel loaded = load_model(path.string());
  std::filesystem::remove(path);
  EXPECT_EQ(loaded.training.point_spacing_min, model.training.point_spacing_min);
  EXPECT_EQ(loaded.training.point_spacing_max, model.training.point_spacing_max);
  EXPECT_EQ(loaded.training.surface_variation_max, model.training.surface_variation_max);
  PointCloud again = trained.test_scene;
  EXPECT_EQ(pipeline::label_cloud(loaded, again, options, RunContext{2}).labels, with_two.labels);
}

// The default CRF training is piecewise: node factors alone, then the one Potts coupling that
// labels the validation scene best, never worse there than no coupling (node-only).
TEST(PipelineLabeling, PiecewiseCrfTrainingKeepsTheCouplingThatValidatesBest) {
  const crf::GraphSettings graph;
  const FeatureSettings features;
  const auto scenes = testing::prepare_training_scenes(
      testing::lms400_scenes(synth::SceneSet::kTrain, 1),
      testing::lms400_scenes(synth::SceneSet::kVal, 1), features, graph);
  const std::vector<SceneData>& validation = scenes.validation;
  pipeline::ModelTrainingOptions options;
  options.iterations = 60;
  ASSERT_EQ(options.objective, crf::TrainingObjective::kPiecewise);
  const auto trained = testing::train_on(scenes, features, graph, options);
  const LabelModel& crf = trained.model;
  EXPECT_EQ(crf.kind, ModelKind::kCrf);
  EXPECT_EQ(crf.training.objective.rfind("piecewise", 0), 0u) << crf.training.objective;
  // A uniform coupling: every class's edge weights are zero but the bias.
  const Eigen::MatrixXf& v = crf.weights.edge_weights;
  ASSERT_EQ(v.rows(), crf.weights.node_weights.rows());
  EXPECT_EQ(v.leftCols(v.cols() - 1).cwiseAbs().maxCoeff(), 0.0f);
  EXPECT_TRUE((v.col(v.cols() - 1).array() == trained.potts_coupling).all());
  const double chosen = pipeline::evaluate_scenes(crf, validation, RunContext{2}).accuracy();
  EXPECT_DOUBLE_EQ(chosen, crf.validation.accuracy);
  EXPECT_GE(
      chosen,
      pipeline::evaluate_scenes(with_coupling(crf, 0.0f), validation, RunContext{2}).accuracy());
  EXPECT_GE(
      chosen,
      pipeline::evaluate_scenes(with_coupling(crf, 1.0f), validation, RunContext{2}).accuracy());
}

// --class-balance: the weights come from the training scenes' labelled points and are recorded
// with alpha in the model's training summary; alpha 0 records none; SVMs and alphas outside
// [0, 1] are refused before any training.
TEST(PipelineLabeling, ClassBalanceIsRecordedInTheTrainingSummary) {
  crf::testing::SceneSpec spec;
  spec.width = 30;
  spec.height = 20;
  spec.dim = kFpfhSize;  // the model file checks it against its features
  spec.region = 5;
  SceneData scene;
  scene.source = "grid";
  scene.graph = crf::testing::make_grid_scene(spec);
  const std::vector<std::uint32_t> class_ids = {1, 2, 4};
  std::vector<int>& labels = scene.graph.labels;
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (labels[i] == 2 && i % 4 != 0) labels[i] = 0;  // class 4 rarer
  for (int y : scene.graph.labels) scene.truth.push_back(class_ids[std::size_t(y)]);
  const std::vector<SceneData> train = {scene};
  pipeline::ModelTrainingOptions options;
  options.kind = ModelKind::kNodeOnly;
  options.iterations = 20;
  options.class_balance = 0.5;
  const FeatureSettings features;
  const crf::GraphSettings graph;
  const LabelModel balanced =
      pipeline::train_label_model(train, {}, class_ids, features, graph, options).model;
  EXPECT_EQ(balanced.training.class_balance, 0.5);
  EXPECT_EQ(balanced.training.class_weights,
            crf::class_balance_weights(balanced.training.class_points, 0.5));
  ASSERT_EQ(balanced.training.class_weights.size(), 3u);
  EXPECT_GT(balanced.training.class_weights[2], 1.2 * balanced.training.class_weights[0]);
  const LabelModel loaded = parse_model(serialize_model(balanced), "balanced");
  EXPECT_EQ(loaded.training.class_weights, balanced.training.class_weights);

  options.class_balance = 0.0;
  const LabelModel plain =
      pipeline::train_label_model(train, {}, class_ids, features, graph, options).model;
  EXPECT_EQ(plain.training.class_balance, 0.0);
  EXPECT_TRUE(plain.training.class_weights.empty());
  EXPECT_FALSE(plain.weights.node_weights.isApprox(balanced.weights.node_weights));

  options.class_balance = 1.5;
  EXPECT_THROW(pipeline::train_label_model(train, {}, class_ids, features, graph, options),
               std::invalid_argument);
  options.class_balance = 0.5;
  options.kind = ModelKind::kSvm;
  EXPECT_THROW(pipeline::train_label_model(train, {}, class_ids, features, graph, options),
               std::invalid_argument);
}

TEST(PipelineLabeling, UnlabelablePointsGetUnknown) {
  PointCloud cloud = small_scene();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.xyz[0] = Vec3f(nan, nan, nan);
  cloud.xyz.push_back(Vec3f(50, 50, 50));  // isolated: no normal, so no descriptor
  cloud.labels.push_back(0);
  cloud.width = std::uint32_t(cloud.xyz.size());
  const auto result = pipeline::label_cloud(testing::zero_node_model(), cloud, {});
  EXPECT_EQ(result.labels.front(), 0u);
  EXPECT_EQ(result.labels.back(), 0u);
  EXPECT_GT(result.labeled_points, cloud.size() / 2);
}

TEST(PipelineLabeling, LabelsOutsideTheModelClassesAreIgnoredInTraining) {
  PointCloud cloud = small_scene();
  const FeatureSettings features;
  pipeline::DescribedCloud described = pipeline::describe_cloud(cloud, features, RunContext{2});
  crf::Graph graph = pipeline::build_scene_graph(cloud, described, {});
  const std::vector<std::uint32_t> only_plane{class_id(PrimitiveClass::kPlane)};
  const crf::LabeledGraph scene =
      pipeline::to_labeled_graph(cloud, std::move(described), std::move(graph), only_plane);
  std::size_t mismatches = 0, planes = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const bool plane = cloud.labels[i] == class_id(PrimitiveClass::kPlane) && scene.graph.active[i];
    planes += plane;
    mismatches += scene.labels[i] != (plane ? 0 : crf::kIgnoreLabel);
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_GT(planes, 0u);
}

}  // namespace
}  // namespace primlabel
