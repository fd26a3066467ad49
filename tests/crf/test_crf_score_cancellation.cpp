// White-box: the CRF score loops of core/crf/src/potentials.cpp honour a stop token and give the
// same values with a token that never stops.
#include <gtest/gtest.h>

#include <cstring>
#include <stop_token>

#include "potentials.hpp"
#include "primlabel/geometry/cancellation.hpp"
#include "crf_scenes.hpp"

namespace primlabel::crf {
namespace {

using detail::RowMatrixXf;
using detail::ScratchBuffer;

struct Fixture {
  testing::SceneSpec spec;
  LabeledGraph scene;
  CrfModel model;
  CrfModel potts;  // edge terms with a bias only (the Potts fast path)
  Fixture() {
    spec.width = 70;
    spec.height = 70;  // 4900 nodes: many blocks of 128
    scene = testing::make_grid_scene(spec);
    model = testing::prototype_model(spec, 1.0f, 0.5f);
    for (int k = 0; k < model.num_classes(); ++k)
      for (int f = 0; f < spec.dim; ++f) model.edge_weights(k, f) = 0.01f * float((k + f) % 5);
    potts = testing::prototype_model(spec, 1.0f, 0.5f);
  }
};

std::stop_token stopped() {
  std::stop_source source;
  source.request_stop();
  return source.get_token();
}

bool same_bits(const float* a, const float* b, std::size_t n) {
  return std::memcmp(a, b, n * sizeof(float)) == 0;
}

TEST(CrfScoreCancellation, AStoppedTokenCancelsEveryScoreLoop) {
  const Fixture f;
  const Graph& graph = f.scene.graph;
  const auto& x = f.scene.descriptors.values;
  const std::stop_token stop = stopped();
  ScratchBuffer<std::uint32_t> edge_of, block_first;
  EXPECT_THROW(detail::number_edges(graph, 2, edge_of, block_first, stop), Cancelled);
  const std::size_t edges = detail::number_edges(graph, 2, edge_of, block_first);
  const int kp = detail::padded_classes(f.model.num_classes());
  std::vector<float> out(std::max(graph.num_nodes(), edges) * kp);
  EXPECT_THROW(detail::node_scores_padded(f.model, x, graph, 2, out.data(), stop), Cancelled);
  for (const CrfModel* model : {&f.model, &f.potts})
    for (bool minus_one : {false, true})
      EXPECT_THROW(detail::edge_terms_padded(*model, x, graph, block_first.data(), 2, minus_one,
                                             out.data(), stop),
                   Cancelled);
}

TEST(CrfScoreCancellation, ANeverStoppedTokenGivesTheSameScores) {
  const Fixture f;
  const Graph& graph = f.scene.graph;
  const auto& x = f.scene.descriptors.values;
  std::stop_source never;
  const std::stop_token token = never.get_token();
  for (int threads : {1, 3}) {
    ScratchBuffer<std::uint32_t> edge_of, block_first, edge_of_t, block_first_t;
    const std::size_t edges = detail::number_edges(graph, 1, edge_of, block_first);
    ASSERT_EQ(detail::number_edges(graph, threads, edge_of_t, block_first_t, token), edges);
    EXPECT_EQ(std::memcmp(edge_of.data(), edge_of_t.data(), graph.num_slots() * 4), 0);
    const int kp = detail::padded_classes(f.model.num_classes());
    std::vector<float> a(graph.num_nodes() * kp), b(graph.num_nodes() * kp);
    detail::node_scores_padded(f.model, x, graph, 1, a.data());
    detail::node_scores_padded(f.model, x, graph, threads, b.data(), token);
    EXPECT_TRUE(same_bits(a.data(), b.data(), a.size()));
    for (const CrfModel* model : {&f.model, &f.potts})
      for (bool minus_one : {false, true}) {
        std::vector<float> e(edges * kp), e_t(edges * kp);
        detail::edge_terms_padded(*model, x, graph, block_first.data(), 1, minus_one, e.data());
        detail::edge_terms_padded(*model, x, graph, block_first_t.data(), threads, minus_one,
                                  e_t.data(), token);
        EXPECT_TRUE(same_bits(e.data(), e_t.data(), e.size())) << minus_one;
      }
  }
}

}  // namespace
}  // namespace primlabel::crf
