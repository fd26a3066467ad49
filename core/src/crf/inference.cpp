#include "primlabel/crf/inference.hpp"

#include <limits>
#include <stdexcept>

#include "../parallel.hpp"
#include "loopy_bp.hpp"
#include "mean_field.hpp"
#include "potentials.hpp"

namespace primlabel::crf {
namespace {

template <typename Matrix>
void fill_outputs(const Matrix& posterior, const CrfModel& model, const Graph& graph,
                  const InferenceOptions& options, InferenceResult& result) {
  const long long n = static_cast<long long>(graph.num_nodes());
  const int k_count = model.num_classes();
  result.labels.assign(n, options.unknown_label);
  if (options.compute_marginals) result.marginals.resize(n, k_count);
  const int threads = detail::useful_threads(options.threads, graph.num_nodes());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (long long i = 0; i < n; ++i) {
    if (!graph.active[i]) {
      if (options.compute_marginals)
        result.marginals.row(i).setConstant(std::numeric_limits<float>::quiet_NaN());
      continue;
    }
    int best = 0;  // first maximum: ties go to the lower class index
    for (int k = 1; k < k_count; ++k)
      if (posterior(i, k) > posterior(i, best)) best = k;
    result.labels[i] = model.class_ids[best];
    if (options.compute_marginals) {
      const double sum = posterior.row(i).template cast<double>().sum();
      result.marginals.row(i) =
          (posterior.row(i).template cast<double>() / sum).template cast<float>();
    }
  }
}

}  // namespace

InferenceResult infer(const CrfModel& model, std::span<const float> descriptors, const Graph& graph,
                      const InferenceOptions& options) {
  detail::check_shapes(model, descriptors, graph);
  if (options.max_iterations < 0) throw std::invalid_argument("infer: max_iterations < 0");
  if (!(options.damping >= 0.0f && options.damping < 1.0f))
    throw std::invalid_argument("infer: damping must be in [0, 1)");
  const int threads = detail::useful_threads(options.threads, graph.num_nodes());
  InferenceResult result;

  const detail::RowMatrixXf theta = detail::node_scores(model, descriptors, graph, threads);
  if (!model.has_edge_terms() || graph.num_slots() == 0) {
    // No coupling: the marginals are the per-node softmax and the MAP is the per-node argmax.
    if (options.compute_marginals)
      fill_outputs(detail::node_potentials(theta, threads), model, graph, options, result);
    else
      fill_outputs(theta, model, graph, options, result);
    result.converged = true;
    return result;
  }

  detail::RowMatrixXf edge_theta = detail::edge_scores(model, descriptors, graph, threads);
  detail::BpSettings settings;
  settings.max_product = options.max_product;
  settings.max_iterations = options.max_iterations;
  settings.damping = options.damping;
  settings.tolerance = options.tolerance;
  settings.threads = threads;
  detail::BpRun run;
  if (options.method == InferenceMethod::kMeanField) {
    const detail::RowMatrixXd q = detail::run_mean_field(graph, theta, edge_theta, settings, run);
    fill_outputs(q, model, graph, options, result);
  } else {
    const detail::RowMatrixXd phi = detail::node_potentials(theta, threads);
    detail::edge_scores_to_potentials_minus_one(edge_theta, threads);  // now psi - 1
    detail::LoopyBp bp(graph, model.num_classes());
    run = bp.run(phi, edge_theta, settings);
    fill_outputs(bp.beliefs(phi, threads), model, graph, options, result);
  }
  result.iterations = run.iterations;
  result.converged = run.converged;
  result.final_change = run.final_change;
  return result;
}

}  // namespace primlabel::crf
