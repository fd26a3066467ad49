#include "mean_field.hpp"

#include <algorithm>
#include <cmath>

namespace primlabel::crf::detail {
namespace {

void softmax_into(const double* a, int k_count, double* q) {
  double mx = a[0];
  for (int k = 1; k < k_count; ++k) mx = std::max(mx, a[k]);
  double sum = 0.0;
  for (int k = 0; k < k_count; ++k) sum += (q[k] = std::exp(a[k] - mx));
  for (int k = 0; k < k_count; ++k) q[k] /= sum;
}

}  // namespace

namespace {

// One node's mean-field update; KC fixed at compile time when possible (see loopy_bp.cpp).
template <int KC>
float update_all(const Graph& graph, const RowMatrixXf& node_scores, const RowMatrixXf& edge_scores,
                 const RowMatrixXd& q, RowMatrixXd& next, double keep, int threads) {
  using ArrayD = Eigen::Array<double, KC, 1>;
  using ConstMapD = Eigen::Map<const ArrayD>;
  using ConstMapF = Eigen::Map<const Eigen::Array<float, KC, 1>>;
  const long long n = static_cast<long long>(graph.num_nodes());
  const int k_count = static_cast<int>(node_scores.cols());
  float max_change = 0.0f;
#pragma omp parallel num_threads(threads) reduction(max : max_change)
  {
    ArrayD a(k_count), fresh(k_count);
#pragma omp for schedule(dynamic, 512)
    for (long long i = 0; i < n; ++i) {
      if (graph.offsets[i] == graph.offsets[i + 1]) continue;  // no neighbours: q is final
      a = ConstMapF(node_scores.row(i).data(), k_count).template cast<double>();
      for (std::uint32_t p = graph.offsets[i]; p < graph.offsets[i + 1]; ++p)
        a += ConstMapD(q.row(graph.neighbors[p]).data(), k_count) *
             ConstMapF(edge_scores.row(p).data(), k_count).template cast<double>();
      fresh = (a - a.maxCoeff()).exp();
      fresh *= 1.0 / fresh.sum();
      const ConstMapD old(q.row(i).data(), k_count);
      Eigen::Map<ArrayD> out(next.row(i).data(), k_count);
      out = (1.0 - keep) * fresh + keep * old;
      max_change = std::max(max_change, static_cast<float>((out - old).abs().maxCoeff()));
    }
  }
  return max_change;
}

float update_all_dispatch(const Graph& graph, const RowMatrixXf& node_scores,
                          const RowMatrixXf& edge_scores, const RowMatrixXd& q, RowMatrixXd& next,
                          double keep, int threads) {
  switch (node_scores.cols()) {
    case 2:
      return update_all<2>(graph, node_scores, edge_scores, q, next, keep, threads);
    case 4:
      return update_all<4>(graph, node_scores, edge_scores, q, next, keep, threads);
    case 8:
      return update_all<8>(graph, node_scores, edge_scores, q, next, keep, threads);
    case 10:
      return update_all<10>(graph, node_scores, edge_scores, q, next, keep, threads);
    case 12:
      return update_all<12>(graph, node_scores, edge_scores, q, next, keep, threads);
    default:
      return update_all<Eigen::Dynamic>(graph, node_scores, edge_scores, q, next, keep, threads);
  }
}

}  // namespace

RowMatrixXd run_mean_field(const Graph& graph, const RowMatrixXf& node_scores,
                           const RowMatrixXf& edge_scores, const BpSettings& settings,
                           BpRun& report) {
  const long long n = static_cast<long long>(graph.num_nodes());
  const int k_count = static_cast<int>(node_scores.cols());
  RowMatrixXd q = RowMatrixXd::Zero(n, k_count);
  // Start from the node-only posterior.
#pragma omp parallel num_threads(settings.threads)
  {
    std::vector<double> a(k_count);
#pragma omp for schedule(static)
    for (long long i = 0; i < n; ++i) {
      if (!graph.active[i]) continue;
      for (int k = 0; k < k_count; ++k) a[k] = node_scores(i, k);
      softmax_into(a.data(), k_count, q.row(i).data());
    }
  }
  RowMatrixXd next = q;
  report = BpRun{};
  for (int iteration = 1; iteration <= settings.max_iterations; ++iteration) {
    const float max_change = update_all_dispatch(graph, node_scores, edge_scores, q, next,
                                                 settings.damping, settings.threads);
    q.swap(next);  // rows without neighbours are never rewritten and start equal in both
    report.iterations = iteration;
    report.final_change = max_change;
    if (max_change < settings.tolerance) {
      report.converged = true;
      break;
    }
  }
  return q;
}

}  // namespace primlabel::crf::detail
