#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <utility>

#include "brute_force.hpp"
#include "crf_scenes.hpp"
#include "primlabel/crf/inference.hpp"

namespace primlabel::crf {
namespace {

using testing::SceneSpec;

// Loopy BP sum- and max-product, and mean-field (max_product is a BP option: one run is enough).
constexpr std::pair<InferenceMethod, bool> kMethods[] = {{InferenceMethod::kLoopyBp, false},
                                                         {InferenceMethod::kLoopyBp, true},
                                                         {InferenceMethod::kMeanField, false}};

// A scan-like grid scene with heavy descriptor noise, and a prototype model that labels it.
struct NoisyScene {
  LabeledGraph scene;
  CrfModel model;
};

NoisyScene noisy_scene(int width, int height, int num_classes) {
  SceneSpec spec;
  spec.width = width;
  spec.height = height;
  spec.num_classes = num_classes;
  spec.noise = 40.0f;
  return {testing::make_grid_scene(spec), testing::prototype_model(spec, 4.0f, 1.0f)};
}

// The fraction of nodes labelled with their true class (class ids are labels + 1).
double accuracy(const InferenceResult& r, const LabeledGraph& scene) {
  const std::size_t n = scene.graph.num_nodes();
  std::size_t correct = 0;
  for (std::size_t i = 0; i < n; ++i) correct += r.labels[i] == std::uint32_t(scene.labels[i] + 1);
  return double(correct) / double(n);
}

// The baseline a CRF must beat: the model without its edge weights labels each node on its own.
InferenceResult infer_node_only(const CrfModel& model, const LabeledGraph& scene) {
  CrfModel node_only = model;
  node_only.edge_weights.setZero();
  return infer(node_only, scene.descriptors, scene.graph, {});
}

// A random model with d = 3 and random descriptors: potentials with no special structure.
struct TinyProblem {
  CrfModel model;
  std::vector<float> descriptors;
  Graph graph;
};

TinyProblem tiny_problem(std::size_t n,
                         const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges,
                         int classes, std::uint32_t seed, float edge_strength,
                         std::vector<float> node_knots = {}) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  std::uniform_real_distribution<float> value(0.0f, 100.0f);
  TinyProblem t;
  std::vector<std::uint32_t> ids(classes);
  for (int k = 0; k < classes; ++k) ids[k] = 10 + k;
  t.model = CrfModel::zeros(ids, 3, 0.01f, std::move(node_knots));
  for (int k = 0; k < classes; ++k) {
    for (int f = 0; f < 4; ++f) {
      t.model.node_weights(k, f) = 2.0f * uniform(rng);
      t.model.edge_weights(k, f) = edge_strength * uniform(rng);
    }
    for (int f = 4; f < t.model.node_feature_dim(); ++f)  // the tent basis has more
      t.model.node_weights(k, f) = 2.0f * uniform(rng);
  }
  t.descriptors.resize(n * 3);
  for (float& v : t.descriptors) v = value(rng);
  t.graph = graph_from_edges(n, edges);
  return t;
}

// Loopy BP to a tight fixed point, to be compared with the brute-force answer: sum-product with
// marginals, or max-product labels.
InferenceResult infer_tightly(const TinyProblem& t, bool max_product) {
  InferenceSettings options;
  options.max_product = max_product;
  options.max_iterations = 200;
  options.tolerance = 1e-7f;
  InferenceOutputs outputs;
  outputs.marginals = !max_product;
  return infer(t.model, t.descriptors, t.graph, options, outputs);
}

const std::vector<std::pair<std::uint32_t, std::uint32_t>> kTree = {{0, 1}, {1, 2}, {1, 3},
                                                                    {3, 4}, {3, 5}, {0, 6}};
const std::vector<std::pair<std::uint32_t, std::uint32_t>> kLoopy = {{0, 1}, {1, 2}, {2, 3},
                                                                     {3, 0}, {0, 2}, {3, 4}};

// With the paper's linear node basis and with the tent basis (checked against the test's own hat
// functions, so the sparse scoring path of inference is covered too).
TEST(CrfInference, SumProductIsExactOnATree) {
  for (const auto& knots : {std::vector<float>{}, std::vector<float>{0.0f, 0.1f, 0.3f, 0.6f, 0.8f}})
    for (std::uint32_t seed = 1; seed <= 5; ++seed) {
      const TinyProblem t = tiny_problem(7, kTree, 3, seed, 2.0f, knots);
      const testing::Exact exact = testing::brute_force(t.model, t.descriptors, t.graph);
      const InferenceResult r = infer_tightly(t, /*max_product=*/false);
      EXPECT_TRUE(r.converged);
      for (std::size_t i = 0; i < 7; ++i)
        for (int k = 0; k < 3; ++k)
          EXPECT_NEAR(r.marginals(i, k), exact.marginals[i][k], 2e-5)
              << knots.size() << " knots, seed " << seed << " node " << i;
    }
}

TEST(CrfInference, MaxProductFindsTheMapLabelling) {
  for (const auto* edges : {&kTree, &kLoopy}) {
    const std::size_t n = edges == &kTree ? 7 : 5;
    for (std::uint32_t seed = 1; seed <= 8; ++seed) {
      const TinyProblem t = tiny_problem(n, *edges, 3, seed, 2.0f);
      const testing::Exact exact = testing::brute_force(t.model, t.descriptors, t.graph);
      const InferenceResult r = infer_tightly(t, /*max_product=*/true);
      for (std::size_t i = 0; i < n; ++i)
        EXPECT_EQ(r.labels[i], t.model.class_ids[exact.map[i]])
            << (edges == &kTree ? "tree" : "loopy") << " seed " << seed << " node " << i;
    }
  }
}

TEST(CrfInference, SameResultForAnyThreadCount) {
  SceneSpec spec;
  spec.width = 100;  // big enough that 3 threads really run (small graphs use one)
  spec.height = 60;
  spec.num_classes = 4;
  const LabeledGraph scene = testing::make_grid_scene(spec);
  const CrfModel model = testing::prototype_model(spec, 3.0f, 0.8f);
  for (const auto method : {InferenceMethod::kLoopyBp, InferenceMethod::kMeanField}) {
    for (const bool max_product : {false, true}) {
      InferenceSettings options;
      options.method = method;
      options.max_product = max_product;
      options.max_iterations = 15;
      const InferenceOutputs outputs{.marginals = true};
      const InferenceResult one =
          infer(model, scene.descriptors, scene.graph, options, outputs, RunContext{1});
      for (int threads : {2, 3}) {
        const InferenceResult many =
            infer(model, scene.descriptors, scene.graph, options, outputs, RunContext{threads});
        EXPECT_EQ(one.labels, many.labels);
        EXPECT_EQ(one.iterations, many.iterations);
        EXPECT_TRUE(one.marginals.cwiseEqual(many.marginals).all());
      }
    }
  }
}

// A kept workspace (reused across graphs of other sizes, methods and thread counts) gives
// bit-identical results to a fresh one.
TEST(CrfInference, WorkspaceReuseGivesIdenticalResults) {
  SceneSpec big;
  big.width = 64;  // 2 threads really run (small graphs use one)
  big.height = 40;
  big.num_classes = 5;
  SceneSpec small = big;
  small.width = 30;
  small.height = 20;
  small.seed = 3;
  const LabeledGraph big_scene = testing::make_grid_scene(big);
  const LabeledGraph small_scene = testing::make_grid_scene(small);
  const CrfModel model = testing::prototype_model(big, 3.0f, 0.8f);
  InferenceWorkspace workspace;
  for (const LabeledGraph* scene : {&big_scene, &small_scene}) {
    for (const auto& [method, max_product] : kMethods) {
      for (const int threads : {1, 2}) {
        InferenceSettings options;
        options.method = method;
        options.max_product = max_product;
        const InferenceOutputs outputs{.marginals = true};
        const RunContext context{threads};
        const InferenceResult fresh =
            infer(model, scene->descriptors, scene->graph, options, outputs, context);
        const InferenceResult kept =
            infer(model, scene->descriptors, scene->graph, options, outputs, context, workspace);
        EXPECT_EQ(fresh.labels, kept.labels);
        EXPECT_EQ(fresh.iterations, kept.iterations);
        EXPECT_TRUE(fresh.marginals.cwiseEqual(kept.marginals).all());
      }
    }
  }
  EXPECT_GT(workspace.bytes(), 0u);
  workspace.release();
  EXPECT_EQ(workspace.bytes(), 0u);
}

// The default stopping rule (belief change, 15 iterations, settled nodes skipped) fires on a
// scan-like scene and labels as well as running BP / mean-field to a tight fixed point.
TEST(CrfInference, DefaultStoppingKeepsAccuracy) {
  const auto [scene, model] = noisy_scene(120, 90, 6);
  const double plain = accuracy(infer_node_only(model, scene), scene);
  for (const auto& [method, max_product] : kMethods) {
    InferenceSettings options;
    options.method = method;
    options.max_product = max_product;
    const InferenceResult quick = infer(model, scene.descriptors, scene.graph, options);
    options.max_iterations = 200;
    options.tolerance = 1e-6f;
    const InferenceResult tight = infer(model, scene.descriptors, scene.graph, options);
    const double a_quick = accuracy(quick, scene), a_tight = accuracy(tight, scene);
    std::printf("method %d max %d: node-only %.4f, default %.4f (%d it%s), tight %.4f (%d it)\n",
                int(method), int(max_product), plain, a_quick, quick.iterations,
                quick.converged ? ", converged" : "", a_tight, tight.iterations);
    EXPECT_GT(a_quick, plain + 0.01);
    EXPECT_GE(a_quick, a_tight - 1e-3);
    if (method == InferenceMethod::kLoopyBp) {
      EXPECT_TRUE(quick.converged);
    }
  }
}

TEST(CrfInference, PointsWithoutDescriptorGetTheUnknownLabel) {
  SceneSpec spec;
  spec.width = 20;
  spec.height = 20;
  std::vector<Vec3f> points;
  LabeledGraph scene = testing::make_grid_scene(spec, &points);
  for (std::size_t i : {0u, 57u, 222u}) scene.descriptors.row(i)[3] = std::nanf("");
  points[300] = Vec3f::Constant(std::nanf(""));
  const Graph graph = build_graph(points, scene.descriptors);
  const CrfModel model = testing::prototype_model(spec, 3.0f, 1.0f);
  for (const auto method : {InferenceMethod::kLoopyBp, InferenceMethod::kMeanField}) {
    InferenceSettings options;
    options.method = method;
    const InferenceOutputs outputs{.marginals = true, .unknown_label = 99};
    const InferenceResult r = infer(model, scene.descriptors, graph, options, outputs);
    for (std::size_t i = 0; i < r.labels.size(); ++i) {
      const bool invalid = i == 0 || i == 57 || i == 222 || i == 300;
      if (invalid) {
        EXPECT_EQ(r.labels[i], 99u);
        EXPECT_TRUE(r.marginals.row(i).array().isNaN().all());
      } else {
        EXPECT_NE(r.labels[i], 99u);
        EXPECT_NEAR(r.marginals.row(i).sum(), 1.0f, 1e-5f);
      }
    }
  }
}

TEST(CrfInference, EmptyGraphAndNodeOnlyModels) {
  const CrfModel model = CrfModel::zeros({1, 2}, 4);
  const Graph empty = graph_from_edges(0, {});
  const InferenceResult r = infer(model, Descriptors(4, {}), empty, {});
  EXPECT_TRUE(r.labels.empty());
  // Typed descriptors must have the model's dimension.
  EXPECT_THROW(infer(model, Descriptors(3, {}), empty, {}), std::invalid_argument);

  // Without edge weights, inference is the per-node argmax.
  SceneSpec spec;
  spec.width = 10;
  spec.height = 10;
  const LabeledGraph scene = testing::make_grid_scene(spec);
  CrfModel node_only = testing::prototype_model(spec, 3.0f, 0.0f);
  const InferenceResult plain = infer(node_only, scene.descriptors, scene.graph, {});
  const Graph no_edges = graph_from_edges(scene.graph.num_nodes(), {});
  CrfModel coupled = testing::prototype_model(spec, 3.0f, 5.0f);
  EXPECT_EQ(infer(coupled, scene.descriptors, no_edges, {}).labels, plain.labels);

  EXPECT_THROW(infer(model, std::vector<float>(3), empty, {}), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::crf
