#pragma once
// Loopy belief propagation for the associative CRF: the one kernel behind inference (sum- and
// max-product labels and marginals) and the Bethe training objective (sum-product, warm-started
// from the previous evaluation's messages).
//
// Synchronous schedule: every iteration computes all new messages from the previous ones, each
// directed slot written by exactly one node, so any thread count gives the same messages.
// Messages are float, normalised to max 1 and floored at kMessageFloor; belief products are
// double (a node of degree 20 multiplies 20 messages). The message on slot p of row i is
// m_{i -> neighbors[p]}. Rows use the padded layouts of potentials.hpp, psi is stored once per
// undirected edge, and the buffers are kept between runs, so repeated runs allocate nothing.
//
// Convergence is tested on what the callers read: a run stops when no node's belief (normalised
// to sum 1) moved more than the tolerance between two of its iterations. A node is skipped while
// its own messages and all its incoming ones moved less than the tolerance in the previous
// iteration (it would only repeat itself); that decision uses the previous iteration alone, so
// results stay identical for any thread count.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "potentials.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::crf::detail {

inline constexpr float kMessageFloor = 1e-30f;
inline constexpr int kMaxBpClasses = 256;

// What a run computes (persisted through crf::InferenceSettings); mean-field reads it too.
struct BpSettings {
  bool max_product = false;
  int max_iterations = 30;
  float damping = 0.5f;  // new = (1 - damping) * update + damping * old
  float tolerance = 1e-3f;
  // false (inference): stop on the beliefs and skip settled nodes, see above. true (the Bethe
  // objective, whose value and gradient are only right at a fixed point): every node is updated
  // in every iteration, and a run stops once no message moved more than the tolerance.
  bool fixed_point = false;
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

// The potentials of one problem, owned by the caller and read by every run until the next reset.
struct BpPotentials {
  const Graph* graph = nullptr;
  int classes = 0;                         // K; rows have padded_classes(K) entries
  const float* phi = nullptr;              // num_nodes x kp, max 1 per active row, pads 0
  const float* psi_minus_one = nullptr;    // num_edges x kp: psi_ij(k) - 1, pads 0
  const std::uint32_t* edge_of = nullptr;  // slot -> undirected edge (number_edges)
};

class BeliefPropagation {
 public:
  // Takes the potentials; the next run starts from uniform messages, and its first iteration is
  // not damped (blending with the uniform start would only delay every message). Throws
  // std::invalid_argument when K is outside [1, kMaxBpClasses].
  void reset(const BpPotentials& potentials);
  // New potentials on the same graph and class count, keeping the messages: the next run starts
  // from them (a warm start, damped from its first iteration).
  void set_potentials(const BpPotentials& potentials);

  // Iterates until converged (see above) or settings.max_iterations. The first iteration of a
  // run has no earlier belief under these potentials to compare with, so it never converges on
  // beliefs; on messages (fixed_point), only the first one from the uniform start cannot.
  // Once context.stop is requested the run returns early with unusable messages; the caller
  // throws Cancelled.
  BpRun run(const BpSettings& settings, const RunContext& context);

  // b_i(k) ∝ phi_i(k) prod_j m_{j->i}(k) from the current messages, normalised to sum 1 (uniform
  // when the product degenerates), into out[0, K); NaN for inactive nodes.
  void beliefs(std::size_t node, std::span<double> out) const;

  // Message m_{i -> neighbors[p]} for slot p: K values (all 1 before the first run).
  const float* message(std::size_t slot) const;
  // All messages (num_slots x padded K), to restore a state after a run that did not converge;
  // empty before the first run.
  std::span<const float> messages() const;
  void set_messages(std::span<const float> messages);

  // labels[i] = class_ids[argmax_k b_i(k)] (first maximum) for active nodes, unknown_label
  // otherwise, and, when `marginals` is not null, beliefs() as float (NaN rows for inactive
  // nodes) into the column-major num_nodes x K matrix `marginals`.
  void outputs(const std::vector<std::uint32_t>& class_ids, std::uint32_t unknown_label,
               const RunContext& context, std::uint32_t* labels, float* marginals) const;

  std::size_t bytes() const;  // memory held by the buffers
  void release();             // frees them (the next run needs a reset)

 private:
  // Fills b[0, kp) with the unnormalised belief product of node i (rescaled to stay in range).
  void product(std::size_t node, double* b) const;
  const float* incoming(std::uint32_t slot) const;

  BpPotentials p_;
  bool uniform_ = true;  // the messages are the uniform start, not stored in messages_
  ScratchBuffer<float> messages_, next_;                   // num_slots x kp; pads are 1
  ScratchBuffer<float> beliefs_;                           // num_nodes x kp: last iteration's
  ScratchBuffer<std::uint8_t> moved_, moved_next_, same_;  // per node, see run()
  ScratchBuffer<float> block_change_;                      // per block of nodes, one iteration
};

}  // namespace primlabel::crf::detail
