#pragma once
// Naive mean-field for the associative CRF, synchronous and damped:
// q_i(k) ∝ exp(theta_i(k) + sum_j q_j(k) theta_ij(k, k)). Each node's row is written by one
// thread from the previous iteration's rows, so the result does not depend on the thread count.
// Float rows on the padded layouts of potentials.hpp; buffers come from the caller's workspace.

#include "inference/belief_propagation.hpp"

namespace primlabel::crf::detail {

struct MeanFieldProblem {
  const Graph* graph = nullptr;
  int classes = 0;                         // K; rows have padded_classes(K) entries
  const float* node_scores = nullptr;      // theta_i: num_nodes x kp
  const float* edge_scores = nullptr;      // theta_ij(k, k) per undirected edge: num_edges x kp
  const std::uint32_t* edge_of = nullptr;  // slot -> undirected edge
};

struct MeanFieldBuffers {
  ScratchBuffer<float> q, next;                         // num_nodes x kp
  ScratchBuffer<std::uint8_t> moved, moved_next, same;  // per node, as in BeliefPropagation
};

// Starts from the node-only posterior; q ends in buffers.q (num_nodes x kp, rows sum to 1, pads
// 0; inactive rows zero). Converged when no q value moved more than the tolerance. Nodes whose q
// and neighbours' q all moved less than the tolerance in the previous iteration are skipped.
BpRun run_mean_field(const MeanFieldProblem& problem, const BpSettings& settings,
                     const RunContext& context, MeanFieldBuffers& buffers);

}  // namespace primlabel::crf::detail
