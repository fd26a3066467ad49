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
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/model.hpp"
#include "primlabel/geometry/descriptors.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::crf {

enum class InferenceMethod {
  kLoopyBp,    // loopy belief propagation (sum-product marginals or max-product labels)
  kMeanField,  // naive mean-field: q_i(k) ∝ exp(theta_i(k) + sum_j q_j(k) theta_ij(k, k))
};

// How a model labels, stored in model files (how a call runs is a RunContext).
struct InferenceSettings {
  InferenceMethod method = InferenceMethod::kLoopyBp;
  bool max_product = false;  // BP only: MAP labels from max-marginals instead of marginals
  // BP and mean-field converge on scan-like graphs within ~15 iterations (damping 0.5); nodes
  // that settled are skipped, so the last iterations cost little.
  int max_iterations = 15;
  // new = (1 - damping) * update + damping * old (BP's first iteration, from uniform messages,
  // is not damped).
  float damping = 0.5f;
  // Converged when no node's result moved more than this between two iterations: BP tests the
  // beliefs (normalised to sum 1, the marginals it returns), mean-field the q values. A node
  // whose messages (q) and whose neighbours' moved less than this in the previous iteration is
  // not recomputed.
  float tolerance = 1e-3f;
};

// What one call returns besides the labels.
struct InferenceOutputs {
  bool marginals = false;           // InferenceResult::marginals
  std::uint32_t unknown_label = 0;  // label of points without a descriptor
};

struct InferenceResult {
  std::vector<std::uint32_t> labels;  // class id per point
  // num_nodes x K when requested: node marginals (max-marginals for max-product), rows sum to 1;
  // NaN rows for points without a descriptor.
  Eigen::MatrixXf marginals;
  int iterations = 0;
  bool converged = false;
  float final_change = 0.0f;  // largest belief (or q) change in the last iteration
};

// The buffers of one inference call (node and edge potentials, messages, beliefs: ~1.2 kB per
// point for K = 10 and a kNN-8 graph). Keep one per calling thread and pass it to every call to
// label repeatedly without allocating (fresh buffers are page-faulted in on every call). Not
// thread-safe; results never depend on it.
class InferenceWorkspace {
 public:
  InferenceWorkspace();
  ~InferenceWorkspace();
  InferenceWorkspace(InferenceWorkspace&&) noexcept;
  InferenceWorkspace& operator=(InferenceWorkspace&&) noexcept;
  InferenceWorkspace(const InferenceWorkspace&) = delete;
  InferenceWorkspace& operator=(const InferenceWorkspace&) = delete;

  std::size_t bytes() const;  // memory held
  void release();             // frees it all

  struct Buffers;  // defined in core/crf/src/inference/inference.cpp

 private:
  friend InferenceResult infer(const CrfModel&, std::span<const float>, const Graph&,
                               const InferenceSettings&, const InferenceOutputs&, const RunContext&,
                               InferenceWorkspace&);
  std::unique_ptr<Buffers> buffers_;
};

// `descriptors` is row-major graph.num_nodes() x model.descriptor_dim. Nodes the graph marks
// inactive get outputs.unknown_label. A model without edge terms (or a graph without edges)
// reduces to the per-node argmax. Throws std::invalid_argument on shape mismatches and
// primlabel::Cancelled when context.stop is requested (checked between iterations and per block
// of nodes inside them). Results do not depend on context.threads.
InferenceResult infer(const CrfModel& model, std::span<const float> descriptors, const Graph& graph,
                      const InferenceSettings& settings = {}, const InferenceOutputs& outputs = {},
                      const RunContext& context = {});
// The same, with the caller's buffers (bit-identical results).
InferenceResult infer(const CrfModel& model, std::span<const float> descriptors, const Graph& graph,
                      const InferenceSettings& settings, const InferenceOutputs& outputs,
                      const RunContext& context, InferenceWorkspace& workspace);
// The same for typed descriptors, whose dimension must be the model's.
InferenceResult infer(const CrfModel& model, const Descriptors& descriptors, const Graph& graph,
                      const InferenceSettings& settings = {}, const InferenceOutputs& outputs = {},
                      const RunContext& context = {});
InferenceResult infer(const CrfModel& model, const Descriptors& descriptors, const Graph& graph,
                      const InferenceSettings& settings, const InferenceOutputs& outputs,
                      const RunContext& context, InferenceWorkspace& workspace);

}  // namespace primlabel::crf
