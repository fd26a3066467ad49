#include "primlabel/crf/inference.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "inference/belief_propagation.hpp"
#include "inference/mean_field.hpp"
#include "mean_field.hpp"
#include "potentials.hpp"
#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel::crf {

using primlabel::detail::parallel_for;
using primlabel::detail::Schedule;

struct InferenceWorkspace::Buffers {
  detail::ScratchBuffer<float> theta;       // node scores, num_nodes x kp
  detail::ScratchBuffer<float> phi;         // node potentials (BP)
  detail::ScratchBuffer<float> edge_terms;  // per undirected edge: psi - 1 (BP) or theta (MF)
  detail::ScratchBuffer<std::uint32_t> edge_of, block_first_edge;
  detail::BeliefPropagation bp;
  detail::MeanFieldBuffers mf;

  std::size_t bytes() const {
    return theta.bytes() + phi.bytes() + edge_terms.bytes() + edge_of.bytes() +
           block_first_edge.bytes() + bp.bytes() + mf.q.bytes() + mf.next.bytes() +
           mf.moved.bytes() * 3;
  }
};

InferenceWorkspace::InferenceWorkspace() = default;
InferenceWorkspace::~InferenceWorkspace() = default;
InferenceWorkspace::InferenceWorkspace(InferenceWorkspace&&) noexcept = default;
InferenceWorkspace& InferenceWorkspace::operator=(InferenceWorkspace&&) noexcept = default;
std::size_t InferenceWorkspace::bytes() const { return buffers_ ? buffers_->bytes() : 0; }
void InferenceWorkspace::release() { buffers_.reset(); }

namespace {

// Labels and marginals from per-node scores on the padded layout: `rows` holds log-scores
// (softmax for the marginals) or probabilities (normalised again in double).
void outputs_from_rows(const float* rows, bool log_scores, const CrfModel& model,
                       const Graph& graph, const InferenceOutputs& outputs, int threads,
                       InferenceResult& result) {
  const long long n = static_cast<long long>(graph.num_nodes());
  const int k_count = model.num_classes();
  const int kp = detail::padded_classes(k_count);
  float* marginals = outputs.marginals ? result.marginals.data() : nullptr;
  parallel_for(
      n, threads, Schedule::Static(), [&] { return std::vector<double>(k_count); },
      [&](std::vector<double>& p, std::ptrdiff_t i) {
        if (!graph.active[i]) {
          result.labels[i] = outputs.unknown_label;
          if (marginals)
            for (int k = 0; k < k_count; ++k)
              marginals[std::size_t(k) * n + i] = std::numeric_limits<float>::quiet_NaN();
          return;
        }
        const float* row = rows + std::size_t(i) * kp;
        int best = 0;  // first maximum: ties go to the lower class index
        for (int k = 1; k < k_count; ++k)
          if (row[k] > row[best]) best = k;
        result.labels[i] = model.class_ids[best];
        if (!marginals) return;
        double sum = 0.0;
        for (int k = 0; k < k_count; ++k)
          sum += (p[k] = log_scores ? std::exp(double(row[k]) - row[best]) : double(row[k]));
        for (int k = 0; k < k_count; ++k)
          marginals[std::size_t(k) * n + i] = static_cast<float>(p[k] / sum);
      });
}

}  // namespace

namespace {
void check_dim(const CrfModel& model, const Descriptors& descriptors) {
  if (descriptors.dim != model.descriptor_dim)
    throw std::invalid_argument("infer: descriptors have dimension " +
                                std::to_string(descriptors.dim) + ", the model " +
                                std::to_string(model.descriptor_dim));
}
}  // namespace

InferenceResult infer(const CrfModel& model, const Descriptors& descriptors, const Graph& graph,
                      const InferenceSettings& settings, const InferenceOutputs& outputs,
                      const RunContext& context) {
  check_dim(model, descriptors);
  return infer(model, std::span<const float>(descriptors.values), graph, settings, outputs,
               context);
}

InferenceResult infer(const CrfModel& model, const Descriptors& descriptors, const Graph& graph,
                      const InferenceSettings& settings, const InferenceOutputs& outputs,
                      const RunContext& context, InferenceWorkspace& workspace) {
  check_dim(model, descriptors);
  return infer(model, std::span<const float>(descriptors.values), graph, settings, outputs, context,
               workspace);
}

InferenceResult infer(const CrfModel& model, std::span<const float> descriptors, const Graph& graph,
                      const InferenceSettings& settings, const InferenceOutputs& outputs,
                      const RunContext& context) {
  InferenceWorkspace workspace;
  return infer(model, descriptors, graph, settings, outputs, context, workspace);
}

InferenceResult infer(const CrfModel& model, std::span<const float> descriptors, const Graph& graph,
                      const InferenceSettings& settings, const InferenceOutputs& outputs,
                      const RunContext& context, InferenceWorkspace& workspace) {
  detail::check_shapes(model, descriptors, graph);
  if (settings.max_iterations < 0) throw std::invalid_argument("infer: max_iterations < 0");
  if (!(settings.damping >= 0.0f && settings.damping < 1.0f))
    throw std::invalid_argument("infer: damping must be in [0, 1)");
  if (!workspace.buffers_) workspace.buffers_ = std::make_unique<InferenceWorkspace::Buffers>();
  InferenceWorkspace::Buffers& ws = *workspace.buffers_;
  const std::size_t n = graph.num_nodes();
  const int k_count = model.num_classes();
  const int kp = detail::padded_classes(k_count);
  const int threads = detail::useful_threads(context.threads, n);
  const RunContext run_context = context.with_threads(threads);
  const std::stop_token& stop = context.stop;
  InferenceResult result;
  result.labels.resize(n);
  if (outputs.marginals) result.marginals.resize(static_cast<Eigen::Index>(n), k_count);

  throw_if_stopped(stop, "inference");
  float* theta = ws.theta.resize(n * kp);
  detail::node_scores_padded(model, descriptors, graph, threads, theta, stop);
  if (!model.has_edge_terms() || graph.num_slots() == 0) {
    // No coupling: the marginals are the per-node softmax and the MAP is the per-node argmax.
    outputs_from_rows(theta, true, model, graph, outputs, threads, result);
    result.converged = true;
    return result;
  }

  const std::size_t edges =
      detail::number_edges(graph, threads, ws.edge_of, ws.block_first_edge, stop);
  float* edge_terms = ws.edge_terms.resize(edges * kp);
  detail::BpSettings bp_settings;
  bp_settings.max_product = settings.max_product;
  bp_settings.max_iterations = settings.max_iterations;
  bp_settings.damping = settings.damping;
  bp_settings.tolerance = settings.tolerance;
  throw_if_stopped(stop, "inference");
  detail::BpRun run;
  if (settings.method == InferenceMethod::kMeanField) {
    detail::edge_terms_padded(model, descriptors, graph, ws.block_first_edge.data(), threads, false,
                              edge_terms, stop);
    detail::MeanFieldProblem problem;
    problem.graph = &graph;
    problem.classes = k_count;
    problem.node_scores = theta;
    problem.edge_scores = edge_terms;
    problem.edge_of = ws.edge_of.data();
    run = detail::run_mean_field(problem, bp_settings, run_context, ws.mf);
    throw_if_stopped(stop, "inference");
    outputs_from_rows(ws.mf.q.data(), false, model, graph, outputs, threads, result);
  } else {
    detail::edge_terms_padded(model, descriptors, graph, ws.block_first_edge.data(), threads, true,
                              edge_terms, stop);
    float* phi = ws.phi.resize(n * kp);
    detail::node_potentials_padded(theta, n, k_count, threads, phi);
    ws.bp.reset({&graph, k_count, phi, edge_terms, ws.edge_of.data()});
    run = ws.bp.run(bp_settings, run_context);
    throw_if_stopped(stop, "inference");
    ws.bp.outputs(model.class_ids, outputs.unknown_label, run_context, result.labels.data(),
                  outputs.marginals ? result.marginals.data() : nullptr);
  }
  result.iterations = run.iterations;
  result.converged = run.converged;
  result.final_change = run.final_change;
  return result;
}

}  // namespace primlabel::crf
