#pragma once
// Labelling a graph with a CrfModel: loopy belief propagation (sum- or max-product) or
// mean-field, both on a synchronous (Jacobi) schedule, so the result is identical for any thread
// count.
//
// Loopy BP exploits the associative potentials: with the cavity h(k) = b_i(k) / m_{j->i}(k),
// a sum-product message is m_{i->j}(l) = S + h(l) (psi_ij(l) - 1), S = sum_k h(k),
// psi_ij(l) = exp(theta_ij(l, l)); a max-product message is
// m_{i->j}(l) = max(max_{k != l} h(k), h(l) psi_ij(l)). Both cost O(K) instead of O(K^2).

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/model.hpp"

namespace primlabel::crf {

enum class InferenceMethod {
  kLoopyBp,    // loopy belief propagation (sum-product marginals or max-product labels)
  kMeanField,  // naive mean-field: q_i(k) ∝ exp(theta_i(k) + sum_j q_j(k) theta_ij(k, k))
};

struct InferenceOptions {
  InferenceMethod method = InferenceMethod::kLoopyBp;
  bool max_product = false;  // BP only: MAP labels from max-marginals instead of marginals
  int max_iterations = 30;
  float damping = 0.5f;     // new = (1 - damping) * update + damping * old
  float tolerance = 1e-3f;  // converged when no message / q value moved more than this
  bool compute_marginals = false;
  std::uint32_t unknown_label = 0;  // label of points without a descriptor
  int threads = 0;                  // 0 = OpenMP default; results do not depend on it
};

struct InferenceResult {
  std::vector<std::uint32_t> labels;  // class id per point
  // num_nodes x K when requested: node marginals (max-marginals for max-product), rows sum to 1;
  // NaN rows for points without a descriptor.
  Eigen::MatrixXf marginals;
  int iterations = 0;
  bool converged = false;
  float final_change = 0.0f;  // largest message (or q) change in the last iteration
};

// `descriptors` is row-major graph.num_nodes() x model.descriptor_dim. Nodes the graph marks
// inactive get options.unknown_label. A model without edge terms (or a graph without edges)
// reduces to the per-node argmax. Throws std::invalid_argument on shape mismatches.
InferenceResult infer(const CrfModel& model, std::span<const float> descriptors, const Graph& graph,
                      const InferenceOptions& options = {});

}  // namespace primlabel::crf
