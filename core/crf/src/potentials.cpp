#include "potentials.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "node_features.hpp"
#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel::crf::detail {

using primlabel::detail::parallel_for;
using primlabel::detail::Schedule;

namespace {

// Blocks are fixed in size and a product never exceeds Eigen's 50k-flop threshold for going
// parallel itself, so every score comes out of the same serial kernel whatever the thread count.
constexpr long long kNodeBlock = 128;
constexpr int kEdgeBatch = 128;
// psi = exp(theta) stays far from float overflow (messages are products of psi and values <= 1).
constexpr float kMaxEdgeScore = 60.0f;
// Edges per stop check in the Potts fill (a plain copy per edge).
constexpr long long kEdgeBlock = 1 << 14;
constexpr const char* kWhat = "computing the CRF scores";

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

std::size_t number_edges(const Graph& graph, int threads, ScratchBuffer<std::uint32_t>& edge_of,
                         ScratchBuffer<std::uint32_t>& block_first_edge,
                         const std::stop_token& stop) {
  const long long n = static_cast<long long>(graph.num_nodes());
  const long long blocks = (n + kNodeBlock - 1) / kNodeBlock;
  std::uint32_t* first = block_first_edge.resize(blocks + 1);
  std::uint32_t* of = edge_of.resize(graph.num_slots());
  const std::uint32_t* offsets = graph.offsets.data();
  const std::uint32_t* neighbors = graph.neighbors.data();
  const std::uint32_t* reverse = graph.reverse.data();
  // Fixed node blocks and a serial prefix sum: the numbering never depends on the threads. Once
  // cancelled, the remaining blocks are skipped.
  parallel_for(blocks, threads, Schedule::Static(), [&](std::ptrdiff_t b) {
    if (stop.stop_requested()) return;
    std::uint32_t count = 0;
    const long long last = std::min(n, (b + 1) * kNodeBlock);
    for (long long i = b * kNodeBlock; i < last; ++i)
      for (std::uint32_t p = offsets[i]; p < offsets[i + 1]; ++p) count += neighbors[p] > i;
    first[b + 1] = count;
  });
  throw_if_stopped(stop, kWhat);
  first[0] = 0;
  for (long long b = 0; b < blocks; ++b) first[b + 1] += first[b];
  parallel_for(blocks, threads, Schedule::Static(), [&](std::ptrdiff_t b) {
    if (stop.stop_requested()) return;
    std::uint32_t e = first[b];
    const long long last = std::min(n, (b + 1) * kNodeBlock);
    for (long long i = b * kNodeBlock; i < last; ++i)
      for (std::uint32_t p = offsets[i]; p < offsets[i + 1]; ++p)
        if (neighbors[p] > i) {
          of[p] = e;
          of[reverse[p]] = e;  // each slot is written once, by the owner of its edge
          ++e;
        }
  });
  throw_if_stopped(stop, kWhat);
  return first[blocks];
}

void node_scores_padded(const CrfModel& model, std::span<const float> descriptors,
                        const Graph& graph, int threads, float* out, const std::stop_token& stop) {
  const long long n = static_cast<long long>(graph.num_nodes());
  const int d = model.descriptor_dim;
  const int dim = model.node_feature_dim();
  const int k_count = model.num_classes();
  const int kp = padded_classes(k_count);
  const long long blocks = (n + kNodeBlock - 1) / kNodeBlock;
  if (!model.node_knots.empty()) {
    // Tent basis: two non-zero values per bin, so a score row is 2d short axpy's over a padded
    // transposed weight table instead of a dense product over d * knots values.
    RowMatrixXf table = RowMatrixXf::Zero(dim, kp);  // node_feature_dim x padded K
    table.leftCols(k_count) = model.node_weights.transpose();
    const float* bias = table.row(dim - 1).data();
    parallel_for(blocks, threads, Schedule::Static(), [&](std::ptrdiff_t b) {
      if (stop.stop_requested()) return;  // cancelled: skip the remaining blocks
      const long long last = std::min(n, (b + 1) * kNodeBlock);
      for (long long i = b * kNodeBlock; i < last; ++i) {
        float* row = out + i * kp;
        if (!graph.active[i]) {
          std::fill_n(row, kp, 0.0f);
          continue;
        }
        std::copy_n(bias, kp, row);
        const float* descriptor = descriptors.data() + i * d;
        for (int f = 0; f < d; ++f) {
          const TentPair p = tent_pair(model.feature_scale * descriptor[f], f, model.node_knots);
          const float* lo = table.data() + std::size_t(p.column) * kp;
          for (int k = 0; k < kp; ++k) row[k] += p.lower * lo[k] + p.upper * lo[k + kp];
        }
      }
    });
    throw_if_stopped(stop, kWhat);
    return;
  }
  const Eigen::MatrixXf weights_t = model.node_weights.transpose();  // node_feature_dim x K
  struct BlockScratch {
    RowMatrixXf features, scores;
  };
  parallel_for(
      blocks, threads, Schedule::Static(),
      [&] {
        return BlockScratch{RowMatrixXf(kNodeBlock, dim), RowMatrixXf(kNodeBlock, k_count)};
      },
      [&](BlockScratch& scratch, std::ptrdiff_t b) {
        if (stop.stop_requested()) return;  // cancelled: skip the remaining blocks
        const long long first = b * kNodeBlock;
        const long long count = std::min(kNodeBlock, n - first);
        for (long long r = 0; r < count; ++r) {
          const long long i = first + r;
          if (graph.active[i])
            node_features(model, descriptors.data() + i * d, scratch.features.row(r).data());
          else
            scratch.features.row(r).setZero();
        }
        scratch.scores.topRows(count).noalias() = scratch.features.topRows(count) * weights_t;
        for (long long r = 0; r < count; ++r) {
          float* row = out + (first + r) * kp;
          std::copy_n(scratch.scores.row(r).data(), k_count, row);
          std::fill(row + k_count, row + kp, 0.0f);
        }
      });
  throw_if_stopped(stop, kWhat);
}

void edge_terms_padded(const CrfModel& model, std::span<const float> descriptors,
                       const Graph& graph, const std::uint32_t* block_first_edge, int threads,
                       bool potentials_minus_one, float* out, const std::stop_token& stop) {
  const long long n = static_cast<long long>(graph.num_nodes());
  const int d = model.descriptor_dim;
  const int k_count = model.num_classes();
  const int kp = padded_classes(k_count);
  const float scale2 = model.feature_scale * model.feature_scale;
  const Eigen::MatrixXf weights_t = model.edge_weights.transpose();  // (d + 1) x K
  const long long blocks = (n + kNodeBlock - 1) / kNodeBlock;
  if (weights_t.topRows(d).isZero(0.0f)) {
    // A Potts coupling (only the bias): the same row for every edge, no feature products.
    std::vector<float> row(std::size_t(kp), 0.0f);
    for (int k = 0; k < k_count; ++k) {
      const float theta = weights_t(d, k);
      row[std::size_t(k)] =
          potentials_minus_one ? std::exp(std::min(theta, kMaxEdgeScore)) - 1.0f : theta;
    }
    const long long edges = static_cast<long long>(block_first_edge[blocks]);
    const long long edge_blocks = (edges + kEdgeBlock - 1) / kEdgeBlock;
    parallel_for(edge_blocks, threads, Schedule::Static(), [&](std::ptrdiff_t eb) {
      if (stop.stop_requested()) return;  // cancelled: skip the remaining blocks
      const long long last = std::min(edges, (eb + 1) * kEdgeBlock);
      for (long long e = eb * kEdgeBlock; e < last; ++e)
        std::copy(row.begin(), row.end(), out + std::size_t(e) * kp);
    });
    throw_if_stopped(stop, kWhat);
    return;
  }
  // Edge feature rows gathered per thread and scored kEdgeBatch at a time.
  struct EdgeBatch {
    RowMatrixXf features, scores;
    std::size_t first = 0;  // edge number of the batch's first row
    int rows = 0;
  };
  const auto flush = [&](EdgeBatch& batch) {
    const int m = batch.rows;
    if (m == 0) return;
    batch.scores.topRows(m).noalias() = batch.features.topRows(m) * weights_t;
    if (potentials_minus_one) {
      // One vectorised exp over the whole batch while it is in cache.
      Eigen::Map<Eigen::ArrayXf> flat(batch.scores.data(), Eigen::Index(m) * k_count);
      flat = flat.min(kMaxEdgeScore).exp() - 1.0f;
    }
    for (int r = 0; r < m; ++r) {
      float* row = out + (batch.first + r) * kp;
      std::copy_n(batch.scores.row(r).data(), k_count, row);
      std::fill(row + k_count, row + kp, 0.0f);
    }
    batch.first += m;
    batch.rows = 0;
  };
  parallel_for(
      blocks, threads, Schedule::Static(),
      [&] {
        return EdgeBatch{RowMatrixXf(kEdgeBatch, d + 1), RowMatrixXf(kEdgeBatch, k_count)};
      },
      [&](EdgeBatch& batch, std::ptrdiff_t b) {
        if (stop.stop_requested()) return;  // cancelled: skip the remaining blocks
        batch.first = block_first_edge[b];
        const long long last = std::min(n, (b + 1) * kNodeBlock);
        for (long long i = b * kNodeBlock; i < last; ++i) {
          const ConstRowMap xi(descriptors.data() + i * d, d);
          for (std::uint32_t p = graph.offsets[i]; p < graph.offsets[i + 1]; ++p) {
            const std::uint32_t j = graph.neighbors[p];
            if (j < i) continue;  // edges in the order number_edges gives them
            batch.features.row(batch.rows).head(d) =
                scale2 * xi.cwiseProduct(ConstRowMap(descriptors.data() + std::size_t(j) * d, d));
            batch.features(batch.rows, d) = 1.0f;
            if (++batch.rows == kEdgeBatch) flush(batch);
          }
        }
        flush(batch);  // batches never span blocks, so they do not depend on the schedule
      });
  throw_if_stopped(stop, kWhat);
}

void node_potentials_padded(const float* theta, std::size_t n, int k_count, int threads,
                            float* phi) {
  const int kp = padded_classes(k_count);
  const long long count = static_cast<long long>(n);
  parallel_for(count, threads, Schedule::Static(), [&](std::ptrdiff_t i) {
    const Eigen::Map<const Eigen::ArrayXf> t(theta + i * kp, k_count);
    Eigen::Map<Eigen::ArrayXf> out(phi + i * kp, kp);
    out.head(k_count) = (t - t.maxCoeff()).exp();
    out.tail(kp - k_count).setZero();
  });
}

}  // namespace primlabel::crf::detail
