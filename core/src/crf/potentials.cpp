#include "potentials.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "../parallel.hpp"

namespace primlabel::crf::detail {
namespace {

// Blocks are fixed in size and a product never exceeds Eigen's 50k-flop threshold for going
// parallel itself, so every score comes out of the same serial kernel whatever the thread count.
constexpr long long kNodeBlock = 128;
constexpr int kEdgeBatch = 128;

using ConstRowMap = Eigen::Map<const Eigen::RowVectorXf>;

}  // namespace

int useful_threads(int requested, std::size_t nodes) {
  constexpr std::size_t kNodesPerThread = 1024;
  const int wanted = primlabel::detail::resolve_threads(requested);
  return static_cast<int>(std::clamp<std::size_t>(nodes / kNodesPerThread, 1, wanted));
}

void check_shapes(const CrfModel& model, std::span<const float> descriptors, const Graph& graph) {
  model.validate();
  if (descriptors.size() != graph.num_nodes() * static_cast<std::size_t>(model.descriptor_dim))
    throw std::invalid_argument("CRF: descriptors are not num_nodes x descriptor_dim (" +
                                std::to_string(descriptors.size()) + " values for " +
                                std::to_string(graph.num_nodes()) + " nodes of dimension " +
                                std::to_string(model.descriptor_dim) + ")");
}

RowMatrixXf node_scores(const CrfModel& model, std::span<const float> descriptors,
                        const Graph& graph, int threads) {
  const long long n = static_cast<long long>(graph.num_nodes());
  const int d = model.descriptor_dim;
  const int k_count = model.num_classes();
  const float scale = model.feature_scale;
  const Eigen::MatrixXf weights_t = model.node_weights.transpose();  // (d + 1) x K
  RowMatrixXf scores(n, k_count);
  const long long blocks = (n + kNodeBlock - 1) / kNodeBlock;
#pragma omp parallel num_threads(threads)
  {
    RowMatrixXf features(kNodeBlock, d + 1);
#pragma omp for schedule(dynamic, 8)
    for (long long b = 0; b < blocks; ++b) {
      const long long first = b * kNodeBlock;
      const long long count = std::min(kNodeBlock, n - first);
      for (long long r = 0; r < count; ++r) {
        const long long i = first + r;
        if (graph.active[i]) {
          features.row(r).head(d) = scale * ConstRowMap(descriptors.data() + i * d, d);
          features(r, d) = 1.0f;
        } else {
          features.row(r).setZero();
        }
      }
      scores.middleRows(first, count).noalias() = features.topRows(count) * weights_t;
    }
  }
  return scores;
}

RowMatrixXf edge_scores(const CrfModel& model, std::span<const float> descriptors,
                        const Graph& graph, int threads) {
  const long long n = static_cast<long long>(graph.num_nodes());
  const int d = model.descriptor_dim;
  const int k_count = model.num_classes();
  RowMatrixXf scores = RowMatrixXf::Zero(static_cast<Eigen::Index>(graph.num_slots()), k_count);
  if (!model.has_edge_terms() || graph.num_slots() == 0) return scores;
  const float scale2 = model.feature_scale * model.feature_scale;
  const Eigen::MatrixXf weights_t = model.edge_weights.transpose();  // (d + 1) x K
  const long long blocks = (n + kNodeBlock - 1) / kNodeBlock;
#pragma omp parallel num_threads(threads)
  {
    RowMatrixXf features(kEdgeBatch, d + 1);
    RowMatrixXf batch_scores(kEdgeBatch, k_count);
    std::vector<std::uint32_t> batch_slots;
    batch_slots.reserve(kEdgeBatch);
    const auto flush = [&] {
      const int m = static_cast<int>(batch_slots.size());
      if (m == 0) return;
      batch_scores.topRows(m).noalias() = features.topRows(m) * weights_t;
      for (int r = 0; r < m; ++r) {
        scores.row(batch_slots[r]) = batch_scores.row(r);
        scores.row(graph.reverse[batch_slots[r]]) = batch_scores.row(r);
      }
      batch_slots.clear();
    };
#pragma omp for schedule(dynamic, 4)
    for (long long b = 0; b < blocks; ++b) {
      const long long last = std::min(n, (b + 1) * kNodeBlock);
      for (long long i = b * kNodeBlock; i < last; ++i) {
        const ConstRowMap xi(descriptors.data() + i * d, d);
        // Each undirected edge is scored once, by its lower endpoint.
        for (std::uint32_t p = graph.offsets[i]; p < graph.offsets[i + 1]; ++p) {
          const std::uint32_t j = graph.neighbors[p];
          if (j < i) continue;
          const int r = static_cast<int>(batch_slots.size());
          features.row(r).head(d) =
              scale2 * xi.cwiseProduct(ConstRowMap(descriptors.data() + std::size_t(j) * d, d));
          features(r, d) = 1.0f;
          batch_slots.push_back(p);
          if (batch_slots.size() == kEdgeBatch) flush();
        }
      }
      flush();  // batches never span blocks, so they do not depend on the schedule
    }
  }
  return scores;
}

}  // namespace primlabel::crf::detail
