#pragma once
// Naive mean-field for the associative CRF, synchronous and damped:
// q_i(k) ∝ exp(theta_i(k) + sum_j q_j(k) theta_ij(k, k)). Each node's row is written by one
// thread from the previous iteration's rows, so the result does not depend on the thread count.

#include "loopy_bp.hpp"

namespace primlabel::crf::detail {

// Returns q (num_nodes x K, rows sum to 1; inactive rows zero). `report` gets the iteration count.
RowMatrixXd run_mean_field(const Graph& graph, const RowMatrixXf& node_scores,
                           const RowMatrixXf& edge_scores, const BpSettings& settings,
                           BpRun& report);

}  // namespace primlabel::crf::detail
