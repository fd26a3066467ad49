// White-box tests of the one loopy BP kernel (core/src/crf/belief_propagation.hpp): inference
// labels and marginals are exactly what the object computes, and the warm start the Bethe
// objective relies on lands on the same fixed point as a cold start.

#include <gtest/gtest.h>

#include <cmath>
#include <stop_token>
#include <vector>

#include "inference/belief_propagation.hpp"
#include "potentials.hpp"
#include "primlabel/crf/inference.hpp"
#include "crf_scenes.hpp"

namespace primlabel::crf {
namespace {

using testing::SceneSpec;

// The potentials inference builds for a model on a graph, in the kernel's layout.
struct Potentials {
  detail::ScratchBuffer<float> theta, phi, psi_minus_one;
  detail::ScratchBuffer<std::uint32_t> edge_of, block_first_edge;

  Potentials(const CrfModel& model, const LabeledGraph& scene, int threads) {
    const std::size_t n = scene.graph.num_nodes();
    const int kp = detail::padded_classes(model.num_classes());
    float* t = theta.resize(n * kp);
    detail::node_scores_padded(model, scene.descriptors.values, scene.graph, threads, t);
    const std::size_t edges = detail::number_edges(scene.graph, threads, edge_of, block_first_edge);
    detail::edge_terms_padded(model, scene.descriptors.values, scene.graph, block_first_edge.data(),
                              threads, true, psi_minus_one.resize(edges * kp));
    detail::node_potentials_padded(t, n, model.num_classes(), threads, phi.resize(n * kp));
  }

  detail::BpPotentials of(const Graph& graph, int classes) const {
    return {&graph, classes, phi.data(), psi_minus_one.data(), edge_of.data()};
  }
};

struct Problem {
  LabeledGraph scene;
  CrfModel model;
};

Problem small_problem() {
  SceneSpec spec;
  spec.width = 40;
  spec.height = 30;
  spec.num_classes = 5;
  spec.dim = 6;
  spec.region = 6;
  Problem p{testing::make_grid_scene(spec), {}};
  p.model = testing::prototype_model(spec, 3.0f, 0.8f);
  return p;
}

detail::BpSettings bp_settings_of(const InferenceSettings& s) {
  return {s.max_product, s.max_iterations, s.damping, s.tolerance};
}

// infer() is this object: its labels are outputs(), its marginals are beliefs() as float, bit
// for bit, for sum- and max-product.
TEST(CrfBeliefPropagation, InferenceReturnsTheObjectsBeliefs) {
  const Problem p = small_problem();
  const Graph& graph = p.scene.graph;
  const int k_count = p.model.num_classes();
  const Potentials potentials(p.model, p.scene, 1);
  for (const bool max_product : {false, true}) {
    InferenceSettings settings;
    settings.max_product = max_product;
    const InferenceOutputs outputs{.marginals = true, .unknown_label = 77};
    const InferenceResult inferred =
        infer(p.model, p.scene.descriptors, graph, settings, outputs, RunContext{1});

    detail::BeliefPropagation bp;
    bp.reset(potentials.of(graph, k_count));
    const detail::BpRun run = bp.run(bp_settings_of(settings), RunContext{2});
    EXPECT_EQ(run.iterations, inferred.iterations);
    EXPECT_EQ(run.converged, inferred.converged);
    EXPECT_EQ(run.final_change, inferred.final_change);

    std::vector<std::uint32_t> labels(graph.num_nodes());
    bp.outputs(p.model.class_ids, 77, RunContext{1}, labels.data(), nullptr);
    EXPECT_EQ(labels, inferred.labels);
    std::vector<double> b(k_count);
    for (std::size_t i = 0; i < graph.num_nodes(); ++i) {
      bp.beliefs(i, b);
      for (int k = 0; k < k_count; ++k)
        ASSERT_EQ(static_cast<float>(b[k]), inferred.marginals(Eigen::Index(i), k))
            << "node " << i << " class " << k << (max_product ? " max" : " sum");
    }
  }
}

// Before any run the messages are uniform, and the beliefs are the node softmax.
TEST(CrfBeliefPropagation, BeforeARunMessagesAreUniform) {
  const Problem p = small_problem();
  const Potentials potentials(p.model, p.scene, 1);
  detail::BeliefPropagation bp;
  bp.reset(potentials.of(p.scene.graph, p.model.num_classes()));
  EXPECT_TRUE(bp.messages().empty());
  for (int k = 0; k < p.model.num_classes(); ++k) EXPECT_EQ(bp.message(5)[k], 1.0f);
  const InferenceResult zero_iterations =
      infer(p.model, p.scene.descriptors, p.scene.graph, InferenceSettings{.max_iterations = 0},
            InferenceOutputs{.marginals = true});
  std::vector<double> b(p.model.num_classes());
  bp.beliefs(9, b);
  for (int k = 0; k < p.model.num_classes(); ++k)
    EXPECT_EQ(static_cast<float>(b[k]), zero_iterations.marginals(9, k));
}

// The Bethe objective's warm start: from the converged messages, a run on the same potentials
// stops after its second iteration at the same fixed point; restored messages are kept exactly.
TEST(CrfBeliefPropagation, AWarmStartKeepsTheFixedPoint) {
  const Problem p = small_problem();
  const Graph& graph = p.scene.graph;
  const int k_count = p.model.num_classes();
  const Potentials potentials(p.model, p.scene, 1);
  const detail::BpSettings tight{false, 300, 0.5f, 1e-6f};
  detail::BeliefPropagation bp;
  bp.reset(potentials.of(graph, k_count));
  const detail::BpRun cold = bp.run(tight, RunContext{1});
  ASSERT_TRUE(cold.converged);
  ASSERT_GT(cold.iterations, 2);
  std::vector<std::vector<double>> before(graph.num_nodes(), std::vector<double>(k_count));
  for (std::size_t i = 0; i < graph.num_nodes(); ++i) bp.beliefs(i, before[i]);
  const std::vector<float> saved(bp.messages().begin(), bp.messages().end());

  bp.set_potentials(potentials.of(graph, k_count));
  const detail::BpRun warm = bp.run(tight, RunContext{1});
  EXPECT_TRUE(warm.converged);
  EXPECT_EQ(warm.iterations, 2);  // the first iteration of a run never converges
  std::vector<double> b(k_count);
  for (std::size_t i = 0; i < graph.num_nodes(); ++i) {
    bp.beliefs(i, b);
    for (int k = 0; k < k_count; ++k) ASSERT_NEAR(b[k], before[i][k], 1e-5) << i;
  }
  bp.set_messages(saved);
  EXPECT_TRUE(std::equal(saved.begin(), saved.end(), bp.messages().begin()));
}

// A stopped RunContext ends the run before its first iteration.
TEST(CrfBeliefPropagation, AStoppedRunContextEndsTheRun) {
  const Problem p = small_problem();
  const Potentials potentials(p.model, p.scene, 1);
  detail::BeliefPropagation bp;
  bp.reset(potentials.of(p.scene.graph, p.model.num_classes()));
  std::stop_source source;
  source.request_stop();
  const detail::BpRun run = bp.run(detail::BpSettings{}, RunContext{1, source.get_token()});
  EXPECT_EQ(run.iterations, 0);
  EXPECT_FALSE(run.converged);
}

}  // namespace
}  // namespace primlabel::crf
