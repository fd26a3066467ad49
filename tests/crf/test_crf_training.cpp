#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <sstream>
#include <string>

#include "brute_force.hpp"
#include "crf_scenes.hpp"
#include "learning/objectives.hpp"  // white-box: the objectives behind train_crf
#include "primlabel/crf/inference.hpp"
#include "primlabel/crf/training.hpp"

namespace primlabel::crf {
namespace {

using testing::SceneSpec;

std::vector<std::uint32_t> ids(int k) {
  std::vector<std::uint32_t> v(k);
  for (int i = 0; i < k; ++i) v[i] = i + 1;
  return v;
}

Eigen::VectorXd random_parameters(Eigen::Index size, std::uint32_t seed, double scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::VectorXd x(size);
  for (Eigen::Index i = 0; i < size; ++i) x(i) = u(rng);
  return x;
}

// The Bethe objective on one thread, its BP run to a 1e-7 tolerance (or `max_iterations`): close
// enough to a fixed point to compare with exact values and finite differences.
std::unique_ptr<detail::Objective> converged_bethe(const std::vector<detail::PreparedScene>& scenes,
                                                   const detail::ParameterShape& shape,
                                                   int max_iterations) {
  detail::BpSettings bp;
  bp.max_iterations = max_iterations;
  bp.tolerance = 1e-7f;
  return detail::make_bethe(scenes, shape, bp, RunContext{1});
}

// Largest |analytic - central difference| over every coordinate.
double gradient_error(detail::Objective& objective, const Eigen::VectorXd& x, double h) {
  Eigen::VectorXd grad(x.size()), scratch(x.size());
  objective.evaluate(x, grad);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    Eigen::VectorXd plus = x, minus = x;
    plus(i) += h;
    minus(i) -= h;
    const double fd =
        (objective.evaluate(plus, scratch) - objective.evaluate(minus, scratch)) / (2 * h);
    worst = std::max(worst, std::abs(fd - grad(i)));
  }
  return worst;
}

LabeledGraph small_scene(std::uint32_t seed, int width = 12, int height = 10) {
  SceneSpec spec;
  spec.width = width;
  spec.height = height;
  spec.num_classes = 3;
  spec.dim = 5;
  spec.region = 4;
  spec.seed = seed;
  LabeledGraph scene = testing::make_grid_scene(spec);
  for (std::size_t i = 0; i < scene.labels.size(); i += 7) scene.labels[i] = kIgnoreLabel;
  return scene;
}

// The tent basis the tests use: knots where the synthetic descriptors' scaled values lie.
const std::vector<float> kKnots = {0.0f, 0.2f, 0.5f, 1.0f};

detail::ParameterShape shape_of(const CrfModel& like, bool edges) {
  return {like.num_classes(), like.node_feature_dim() - 1, like.descriptor_dim, edges};
}

// Calls check(prepared, shape, what) on scenes 1 and 2 prepared for three classes in each basis
// (linear, tent knots), with edges (pseudo-likelihood) and without (node-only); `what` names the
// case for a failure message.
template <class Check>
void for_each_objective_setup(Check check) {
  const std::vector<LabeledGraph> scenes = {small_scene(1), small_scene(2)};
  for (const auto& knots : {std::vector<float>{}, kKnots}) {
    const CrfModel like = CrfModel::zeros(ids(3), 5, 0.01f, knots);
    for (const bool edges : {true, false}) {
      const auto prepared = detail::prepare_scenes(scenes, like, edges);
      const std::string what =
          std::string(edges ? "PL" : "node-only") + ", " + std::to_string(knots.size()) + " knots";
      check(prepared, shape_of(like, edges), what);
    }
  }
}

TEST(CrfTraining, PseudoLikelihoodAndNodeOnlyGradientsMatchFiniteDifferences) {
  for_each_objective_setup(
      [](const auto& prepared, const detail::ParameterShape& shape, const std::string& what) {
        auto objective = detail::make_pseudo_likelihood(prepared, shape, 2);
        const Eigen::VectorXd x = random_parameters(shape.size(), 3, 1.0);
        EXPECT_LT(gradient_error(*objective, x, 1e-5), 1e-7) << what;
      });
}

// Class weights scale each point's term by its label's weight: the analytic gradient still matches
// central differences, for pseudo-likelihood and node-only, in both bases.
TEST(CrfTraining, WeightedGradientsMatchFiniteDifferences) {
  const std::vector<double> weights = {0.3, 1.0, 4.5};
  for_each_objective_setup(
      [&](const auto& prepared, const detail::ParameterShape& shape, const std::string& what) {
        auto weighted = detail::make_pseudo_likelihood(prepared, shape, 2, weights);
        auto plain = detail::make_pseudo_likelihood(prepared, shape, 2);
        const Eigen::VectorXd x = random_parameters(shape.size(), 3, 1.0);
        EXPECT_LT(gradient_error(*weighted, x, 1e-5), 1e-7) << what;
        Eigen::VectorXd g(x.size());
        EXPECT_GT(std::abs(weighted->evaluate(x, g) - plain->evaluate(x, g)), 1e-3);  // it bites
      });
}

// alpha = 0 is today's objective exactly: unit weights give the same value and gradient bit for
// bit, equal weights of any size within rounding (only ratios matter), and train_crf the same
// model.
TEST(CrfTraining, UnitClassWeightsAreTheUnweightedObjective) {
  for_each_objective_setup([](const auto& prepared, const detail::ParameterShape& shape,
                              const std::string& what) {
    const Eigen::VectorXd x = random_parameters(shape.size(), 5, 1.0);
    Eigen::VectorXd g_plain(x.size()), g_unit(x.size()), g_equal(x.size());
    const double plain = detail::make_pseudo_likelihood(prepared, shape, 2)->evaluate(x, g_plain);
    const double unit =
        detail::make_pseudo_likelihood(prepared, shape, 2, {1.0, 1.0, 1.0})->evaluate(x, g_unit);
    const double equal =
        detail::make_pseudo_likelihood(prepared, shape, 2, {2.5, 2.5, 2.5})->evaluate(x, g_equal);
    EXPECT_EQ(plain, unit) << what;
    EXPECT_TRUE(g_plain.cwiseEqual(g_unit).all()) << what;
    EXPECT_NEAR(plain, equal, 1e-12) << what;
    EXPECT_LT((g_plain - g_equal).cwiseAbs().maxCoeff(), 1e-12) << what;
  });
  const std::vector<LabeledGraph> scenes = {small_scene(1), small_scene(2)};
  const std::vector<std::uint64_t> counts = {500, 30, 2};
  TrainingOptions options;
  options.objective = TrainingObjective::kNodeOnly;
  options.max_iterations = 20;
  const TrainingResult plain = train_crf(scenes, {}, ids(3), options);
  options.class_weights = class_balance_weights(counts, 0.0);
  const TrainingResult alpha0 = train_crf(scenes, {}, ids(3), options);
  EXPECT_TRUE(plain.model.node_weights.cwiseEqual(alpha0.model.node_weights).all());
  EXPECT_EQ(plain.objective, alpha0.objective);
}

TEST(CrfTraining, ClassBalanceWeights) {
  const std::vector<std::uint64_t> counts = {900, 90, 0, 10};  // N = 1000, K = 3 with points
  EXPECT_EQ(class_balance_weights(counts, 0.0), std::vector<double>(4, 1.0));
  const std::vector<double> full = class_balance_weights(counts, 1.0);
  EXPECT_NEAR(full[0], 1000.0 / (3 * 900), 1e-15);
  EXPECT_NEAR(full[1], 1000.0 / (3 * 90), 1e-15);
  EXPECT_EQ(full[2], 1.0);  // no points, nothing to weight
  EXPECT_NEAR(full[3], 1000.0 / (3 * 10), 1e-15);
  // alpha = 1: every class with points weighs N / K in total.
  for (std::size_t c : {0u, 1u, 3u}) EXPECT_NEAR(full[c] * double(counts[c]), 1000.0 / 3, 1e-9);
  const std::vector<double> half = class_balance_weights(counts, 0.5);
  EXPECT_NEAR(half[3], std::sqrt(full[3]), 1e-12);
  EXPECT_THROW(class_balance_weights(counts, -0.1), std::invalid_argument);
  EXPECT_THROW(class_balance_weights(counts, 1.5), std::invalid_argument);
  EXPECT_THROW(class_balance_weights(std::vector<std::uint64_t>{0, 0}, 0.5), std::invalid_argument);
}

// Two overlapping classes, one 4% of the points: the unweighted likelihood puts the boundary deep
// inside the rare class (few of its points are worth the errors on the common one); balanced
// weights move it back to the middle, and the rare class's recall rises.
LabeledGraph rare_class_scene(std::uint32_t seed, std::size_t n) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution rare(0.04);
  std::normal_distribution<float> common_value(40.0f, 8.0f), rare_value(56.0f, 8.0f);
  LabeledGraph scene;
  scene.descriptors.dim = 1;
  scene.graph = graph_from_edges(n, {});
  for (std::size_t i = 0; i < n; ++i) {
    const bool r = rare(rng);
    scene.descriptors.values.push_back(
        std::clamp(r ? rare_value(rng) : common_value(rng), 0.f, 100.f));
    scene.labels.push_back(r ? 1 : 0);
  }
  return scene;
}

double class_recall(const CrfModel& model, const LabeledGraph& scene, int k) {
  const InferenceResult r = infer(model, scene.descriptors, scene.graph, {});
  std::size_t support = 0, hits = 0;
  for (std::size_t i = 0; i < scene.labels.size(); ++i) {
    if (scene.labels[i] != k) continue;
    ++support;
    hits += r.labels[i] == model.class_ids[k] ? 1 : 0;
  }
  return double(hits) / double(support);
}

TEST(CrfTraining, ClassWeightsRaiseTheRecallOfARareClass) {
  const std::vector<LabeledGraph> train = {rare_class_scene(1, 5000)};
  const std::vector<LabeledGraph> test = {rare_class_scene(2, 5000)};
  std::vector<std::uint64_t> counts(2, 0);
  for (int y : train[0].labels) ++counts[std::size_t(y)];
  TrainingOptions options;
  options.objective = TrainingObjective::kNodeOnly;
  options.l2 = 1e-6;  // as pipeline::train_label_model
  options.node_knots = {};
  options.max_iterations = 200;
  const CrfModel plain = train_crf(train, {}, ids(2), options).model;
  options.class_weights = class_balance_weights(counts, 1.0);
  const CrfModel balanced = train_crf(train, {}, ids(2), options).model;
  const double plain_recall = class_recall(plain, test[0], 1);
  const double balanced_recall = class_recall(balanced, test[0], 1);
  std::printf("rare class recall: unweighted %.3f, balanced %.3f; accuracy %.3f, %.3f\n",
              plain_recall, balanced_recall, labeled_accuracy(plain, test, {}),
              labeled_accuracy(balanced, test, {}));
  EXPECT_LT(plain_recall, 0.5);
  EXPECT_GT(balanced_recall, 0.75);
  EXPECT_GT(class_recall(balanced, test[0], 0), 0.75);  // not everything called rare
}

// On a tree the Bethe free energy is exact, so the BP objective is the exact negative
// log-likelihood and its gradient the exact gradient.
TEST(CrfTraining, BetheObjectiveIsExactOnATree) {
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> tree = {{0, 1}, {1, 2}, {1, 3},
                                                                     {3, 4}, {3, 5}, {0, 6}};
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> value(0.0f, 100.0f);
  LabeledGraph scene;
  scene.descriptors = Descriptors::filled(7, 3, 0.0f);
  for (float& v : scene.descriptors.values) v = value(rng);
  scene.graph = graph_from_edges(7, tree);
  scene.labels = {0, 0, 1, 2, 2, 1, 0};
  const std::vector<LabeledGraph> scenes = {scene};
  for (const auto& knots : {std::vector<float>{}, kKnots}) {
    const CrfModel like = CrfModel::zeros(ids(3), 3, 0.01f, knots);
    const auto prepared = detail::prepare_scenes(scenes, like, true);
    const detail::ParameterShape shape = shape_of(like, true);
    auto objective = converged_bethe(prepared, shape, 300);
    const Eigen::VectorXd x = random_parameters(shape.size(), 11, 1.5);
    Eigen::VectorXd grad(x.size());
    const double value_bethe = objective->evaluate(x, grad);

    const CrfModel model = detail::model_from_parameters(x, shape, like);
    const testing::Exact exact = testing::brute_force(model, scene.descriptors.values, scene.graph);
    const double exact_nll = (exact.log_z - exact.score(scene.labels)) / 7.0;
    EXPECT_NEAR(value_bethe, exact_nll, 1e-4) << knots.size() << " knots";
    EXPECT_LT(gradient_error(*objective, x, 1e-4), 2e-3) << knots.size() << " knots";
  }
}

// On a loopy graph the Bethe value is an approximation, but at a BP fixed point its gradient is
// still exactly the BP marginals' expectation: the analytic gradient (from the kernel's beliefs
// and messages) matches central differences of the value.
TEST(CrfTraining, BetheGradientMatchesFiniteDifferencesOnALoopyGraph) {
  const std::vector<LabeledGraph> scenes = {small_scene(7, 6, 5)};
  const CrfModel like = CrfModel::zeros(ids(3), 5, 0.01f, kKnots);
  auto prepared = detail::prepare_scenes(scenes, like, true);
  // As train_crf does: the graph over the labelled nodes only.
  std::vector<std::uint8_t> labelled(scenes[0].labels.size());
  for (std::size_t i = 0; i < labelled.size(); ++i) labelled[i] = scenes[0].labels[i] >= 0;
  const Graph restricted = restrict_graph(scenes[0].graph, labelled);
  prepared[0].graph = &restricted;
  ASSERT_GT(restricted.num_edges(), restricted.num_active());  // loops
  const detail::ParameterShape shape = shape_of(like, true);
  auto objective = converged_bethe(prepared, shape, 500);
  const Eigen::VectorXd x = random_parameters(shape.size(), 13, 0.5);
  EXPECT_LT(gradient_error(*objective, x, 1e-4), 2e-3);
}

struct Accuracies {
  double node_only, pseudo_likelihood, bethe;
};

TEST(CrfTraining, CrfBeatsNodeOnlyOnHeldOutData) {
  SceneSpec spec;
  spec.width = 48;
  spec.height = 48;
  spec.num_classes = 3;
  spec.noise = 100.0f;
  auto scenes = testing::held_out_scenes(spec, 1, 2);
  const std::vector<LabeledGraph> train = {std::move(scenes.train)};
  const std::vector<LabeledGraph> test = {std::move(scenes.test)};
  InferenceSettings inference;
  const auto run = [&](TrainingObjective objective) {
    TrainingOptions options;
    options.objective = objective;
    options.max_iterations = 40;
    const TrainingResult r = train_crf(train, {}, ids(3), options);
    const double acc = labeled_accuracy(r.model, test, inference);
    std::printf("%-18s %3d iterations  objective %.4f  held-out accuracy %.3f  %s\n",
                objective == TrainingObjective::kNodeOnly           ? "node-only"
                : objective == TrainingObjective::kPseudoLikelihood ? "pseudo-likelihood"
                                                                    : "bethe-bp",
                r.iterations, r.objective, acc, r.message.c_str());
    return acc;
  };
  const double node_only = run(TrainingObjective::kNodeOnly);
  const double pl = run(TrainingObjective::kPseudoLikelihood);
  const double bethe = run(TrainingObjective::kBetheBp);
  EXPECT_LT(node_only, 0.95);
  EXPECT_GT(pl, node_only + 0.05);
  EXPECT_GT(bethe, node_only + 0.05);
}

TEST(CrfTraining, SameModelForOneAndTwoThreads) {
  // Big enough (2 x 1200 nodes) that two threads really run; small problems use one.
  const std::vector<LabeledGraph> scenes = {small_scene(3, 40, 30), small_scene(4, 40, 30)};
  for (const auto objective : {TrainingObjective::kPseudoLikelihood, TrainingObjective::kBetheBp,
                               TrainingObjective::kNodeOnly}) {
    TrainingOptions options;
    options.objective = objective;
    options.max_iterations = 10;
    const TrainingResult one = train_crf(scenes, {}, ids(3), options, RunContext{1});
    const TrainingResult two = train_crf(scenes, {}, ids(3), options, RunContext{2});
    EXPECT_TRUE(one.model.node_weights.cwiseEqual(two.model.node_weights).all());
    EXPECT_TRUE(one.model.edge_weights.cwiseEqual(two.model.edge_weights).all());
    EXPECT_EQ(one.objective, two.objective);
  }
}

TEST(CrfTraining, ReportsTheTrainingCurve) {
  const std::vector<LabeledGraph> train = {small_scene(5)};
  const std::vector<LabeledGraph> validation = {small_scene(6)};
  std::vector<TrainingIteration> seen;
  TrainingOptions options;
  options.max_iterations = 8;
  options.on_iteration = [&](const TrainingIteration& it) { seen.push_back(it); };
  const TrainingResult r = train_crf(train, validation, ids(3), options);
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.size(), r.curve.size());
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i].iteration, int(i) + 1);
    EXPECT_GE(seen[i].train_accuracy, 0.0);
    EXPECT_LE(seen[i].train_accuracy, 1.0);
    EXPECT_FALSE(std::isnan(seen[i].validation_accuracy));
    if (i > 0) EXPECT_LE(seen[i].objective, seen[i - 1].objective + 1e-12);
  }
  std::ostringstream csv;
  write_training_curve_csv(csv, r.curve);
  EXPECT_EQ(
      csv.str().rfind("iteration,objective,train_accuracy,validation_accuracy,seconds\n1,", 0), 0u);

  // Without a validation set the column is empty.
  const TrainingResult no_validation = train_crf(train, {}, ids(3), options);
  EXPECT_TRUE(std::isnan(no_validation.curve.front().validation_accuracy));
  EXPECT_NE(training_curve_csv_row(no_validation.curve.front()).find(",,"), std::string::npos);
}

TEST(CrfTraining, RejectsInconsistentData) {
  std::vector<LabeledGraph> scenes = {small_scene(7)};
  scenes[0].labels[3] = 5;
  EXPECT_THROW(train_crf(scenes, {}, ids(3), {}), std::invalid_argument);
  EXPECT_THROW(train_crf({}, {}, ids(3), {}), std::invalid_argument);
  TrainingOptions bad_knots;
  bad_knots.node_knots = {0.0f, 0.5f, 0.5f};
  const std::vector<LabeledGraph> good = {small_scene(7)};
  EXPECT_THROW(train_crf(good, {}, ids(3), bad_knots), std::invalid_argument);
  TrainingOptions bad_weights;
  bad_weights.class_weights = {1.0, 2.0};  // not one per class
  EXPECT_THROW(train_crf(good, {}, ids(3), bad_weights), std::invalid_argument);
  bad_weights.class_weights = {1.0, 0.0, 2.0};
  EXPECT_THROW(train_crf(good, {}, ids(3), bad_weights), std::invalid_argument);
  bad_weights.class_weights = {1.0, 1.0, 2.0};
  bad_weights.objective = TrainingObjective::kBetheBp;  // log Z has no per-point terms
  EXPECT_THROW(train_crf(good, {}, ids(3), bad_weights), std::invalid_argument);
}

// One descriptor value whose class is a band in the middle of its range: a single weight per bin
// (the paper's linear basis) can only threshold it, a piecewise-linear function can carve it.
LabeledGraph band_scene(std::uint32_t seed, std::size_t n) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.0f, 100.0f);
  LabeledGraph scene;
  scene.descriptors.dim = 1;
  scene.graph = graph_from_edges(n, {});
  for (std::size_t i = 0; i < n; ++i) {
    const float v = value(rng);
    scene.descriptors.values.push_back(v);
    scene.labels.push_back(v > 30.0f && v < 60.0f ? 1 : 0);
  }
  return scene;
}

TEST(CrfTraining, TentBasisLearnsWhatTheLinearBasisCannot) {
  const std::vector<LabeledGraph> train = {band_scene(1, 800)};
  const std::vector<LabeledGraph> test = {band_scene(2, 800)};
  TrainingOptions options;
  options.objective = TrainingObjective::kNodeOnly;
  options.l2 = 1e-6;
  options.max_iterations = 200;
  options.node_knots = {};
  const double linear = labeled_accuracy(train_crf(train, {}, ids(2), options).model, test, {});
  options.node_knots = {0.0f, 0.2f, 0.4f, 0.6f, 0.8f, 1.0f};
  const TrainingResult tent = train_crf(train, {}, ids(2), options);
  EXPECT_EQ(tent.model.node_weights.cols(), 1 * 6 + 1);
  const double tent_accuracy = labeled_accuracy(tent.model, test, {});
  std::printf("band: linear basis %.3f, tent basis %.3f\n", linear, tent_accuracy);
  EXPECT_LT(linear, 0.8);  // about the majority share, 0.7
  EXPECT_GT(tent_accuracy, 0.93);
}

}  // namespace
}  // namespace primlabel::crf
