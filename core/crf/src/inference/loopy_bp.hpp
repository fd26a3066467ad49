#pragma once
// Loopy belief propagation with associative pairwise potentials in O(K) per message, on a
// synchronous schedule: every iteration computes all new messages from the previous ones, each
// directed slot written by exactly one node, so any thread count gives the same messages.
//
// Messages are float, normalised to max 1 and floored at kMessageFloor; the belief products are
// double (a node of degree 20 multiplies 20 messages). The message on slot p of row i is
// m_{i -> neighbors[p]}. The messages persist between runs, so training can warm-start.

#include <stop_token>
#include <vector>

#include "potentials.hpp"

namespace primlabel::crf::detail {

inline constexpr float kMessageFloor = 1e-30f;
inline constexpr int kMaxBpClasses = 256;

struct BpSettings {
  bool max_product = false;
  int max_iterations = 30;
  float damping = 0.5f;
  float tolerance = 1e-3f;
  int threads = 1;
  // Once stopped, the run returns early (between iterations, or skipping the rest of one) with
  // unusable messages; the caller throws Cancelled.
  std::stop_token stop;
};

struct BpRun {
  int iterations = 0;
  bool converged = false;
  float final_change = 0.0f;

  // Records an iteration's largest change; true (converged) once it is below the tolerance.
  bool record(int iteration, float change, float tolerance) {
    iterations = iteration;
    final_change = change;
    converged = change < tolerance;
    return converged;
  }
};

// phi_i(k) = exp(theta_i(k) - max_k theta_i(k)): num_nodes x K, max 1 per row.
RowMatrixXd node_potentials(const RowMatrixXf& node_scores, int threads);

// Turns theta_ij(k, k) into psi_ij(k) - 1 = exp(theta_ij(k, k)) - 1, in place (theta is capped
// at 60 so psi stays far from float overflow).
void edge_scores_to_potentials_minus_one(RowMatrixXf& edge_scores, int threads);

class LoopyBp {
 public:
  LoopyBp(const Graph& graph, int num_classes);

  // Sets every message to 1 (uniform).
  void reset();

  // Iterates until the largest message change is below the tolerance or max_iterations.
  BpRun run(const RowMatrixXd& phi, const RowMatrixXf& psi_minus_one, const BpSettings& settings);

  // b_i(k) ∝ phi_i(k) prod_j m_{j->i}(k), rows normalised to sum 1; inactive rows are zero.
  RowMatrixXd beliefs(const RowMatrixXd& phi, int threads) const;

  // All messages (slot-major), e.g. to restore a state after a run that did not converge.
  const std::vector<float>& messages() const { return messages_; }
  void set_messages(const std::vector<float>& messages) { messages_ = messages; }

  // Message m_{i -> neighbors[p]} for slot p.
  const float* message(std::size_t slot) const { return messages_.data() + slot * num_classes_; }

 private:
  const Graph& graph_;
  int num_classes_;
  std::vector<float> messages_;
  std::vector<float> next_;
};

// ---- Inference fast path -----------------------------------------------------------------------
// The same messages as LoopyBp, on the padded layouts of potentials.hpp, with psi stored once per
// undirected edge and buffers owned by the caller (InferenceWorkspace), so repeated calls allocate
// nothing. Convergence is tested on what inference returns: the run stops when no node's belief
// (normalised to sum 1) moved more than the tolerance between two iterations. A node is skipped
// while its own messages and all its incoming ones moved less than the tolerance in the previous
// iteration (it would only repeat itself); that decision uses the previous iteration alone, so
// results stay identical for any thread count.
struct FastBpProblem {
  const Graph* graph = nullptr;
  int classes = 0;                         // K; rows have padded_classes(K) entries
  const float* phi = nullptr;              // num_nodes x kp, max 1 per active row, pads 0
  const float* psi_minus_one = nullptr;    // num_edges x kp, pads 0
  const std::uint32_t* edge_of = nullptr;  // slot -> undirected edge
};

struct FastBpBuffers {
  ScratchBuffer<float> messages, next;  // num_slots x kp; pads are 1
  ScratchBuffer<float> beliefs;         // num_nodes x kp: the last iteration's beliefs
  ScratchBuffer<std::uint8_t> moved, moved_next, same;  // per node, see run_fast_bp
};

// Synchronous damped BP from uniform messages; the messages end in buffers.messages. The first
// iteration is not damped: blending with the uniform start would only delay every message.
BpRun run_fast_bp(const FastBpProblem& problem, const BpSettings& settings, FastBpBuffers& buffers);

// From the final messages: labels[i] = class_ids[argmax_k b_i(k)] (first maximum) for active
// nodes, unknown_label otherwise, and, when `marginals` is not null, b_i normalised to sum 1
// (NaN rows for inactive nodes) into the column-major num_nodes x K matrix `marginals`.
void fast_bp_outputs(const FastBpProblem& problem, const FastBpBuffers& buffers,
                     const std::vector<std::uint32_t>& class_ids, std::uint32_t unknown_label,
                     int threads, std::uint32_t* labels, float* marginals);

}  // namespace primlabel::crf::detail
