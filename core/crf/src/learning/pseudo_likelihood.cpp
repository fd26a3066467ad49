// Pseudo-likelihood  sum_i log p(y_i | y_N(i), x)  and, without edges, logistic regression.
//
// p(y_i = k | y_N(i)) ∝ exp(w_k . x_i + sum_{j in N(i), y_j = k} v_k . e_ij): only neighbours
// labelled k contribute to class k, so per node the edge features are summed per neighbour label
// (A_i(k) = sum_{j: y_j = k} e_ij) and each class costs one dot product. Without edges a block
// of nodes is two matrix products (scores, then the gradient) in the identity basis, or 2d short
// axpy's per node in the tent basis: the fast path of node-only and piecewise training.
// Class weights scale a point's loss and its residual by the weight of its label; the sum is then
// divided by the weighted count (with all weights 1, the same numbers bit for bit).

#include <algorithm>
#include <cmath>
#include <utility>

#include "learning/objectives.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel::crf::detail {

using primlabel::detail::parallel_for;
using primlabel::detail::Schedule;

namespace {

class PseudoLikelihood final : public Objective {
 public:
  PseudoLikelihood(const std::vector<PreparedScene>& scenes, const ParameterShape& shape,
                   int threads, std::vector<double> class_weights)
      : scenes_(scenes),
        shape_(shape),
        threads_(threads),
        blocks_(node_blocks(scenes)),
        weights_(std::move(class_weights)) {
    if (weights_.empty()) weights_.assign(std::size_t(shape_.classes), 1.0);
    // Per class, then in class order: the same sum for any scene layout.
    std::vector<std::size_t> counts(weights_.size(), 0);
    for (const auto& s : scenes_)
      for (int y : s.labels)
        if (y >= 0) ++counts[std::size_t(y)];
    for (std::size_t c = 0; c < counts.size(); ++c) labelled_ += weights_[c] * double(counts[c]);
  }

  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) override {
    const long long block_count = static_cast<long long>(blocks_.size());
    partial_grad_.setZero(x.size(), block_count);
    partial_loss_.setZero(block_count);
    if (shape_.edges)
      evaluate_blocks_with_edges(x);
    else
      evaluate_blocks_node_only(x);
    return sum_blocks(partial_grad_, partial_loss_, labelled_, gradient);
  }

 private:
  // Scores in, -w_{y_i} log p(y_i) out; the row becomes w_{y_i} (p - [k == y_i]) (zeros for an
  // ignored node).
  double softmax_residual(Eigen::Ref<Eigen::RowVectorXd> scores, int yi) const {
    if (yi < 0) {
      scores.setZero();
      return 0.0;
    }
    const double top = scores.maxCoeff();
    const double yi_score = scores(yi);
    scores = (scores.array() - top).exp();
    const double z = scores.sum();
    scores /= z;
    scores(yi) -= 1.0;  // d(-log p(y_i)) / d score = p - [k == y_i]
    const double w = weights_[std::size_t(yi)];
    scores *= w;
    return -w * (yi_score - top - std::log(z));
  }

  // Node-only over one block in the tent basis: each bin touches two rows of w_t (node_row x K),
  // so scores and gradient are 2d short axpy's per node instead of a dense product over
  // d * knots values. Fills grad_t (node_row x K); returns the block's loss.
  double tent_block(const NodeBlock& block, const RowMatrixXd& w_t, RowMatrixXd& residual,
                    RowMatrixXd& grad_t) const {
    const PreparedScene& scene = scenes_[block.scene];
    const int k_count = shape_.classes;
    const int row = shape_.node_row();
    const int d = shape_.edge_dim;
    residual.resize(block.count, k_count);
    grad_t.setZero(row, k_count);
    double* bias_grad = grad_t.data() + std::size_t(row - 1) * k_count;
    double loss = 0.0;
    for (long long r = 0; r < block.count; ++r) {
      const long long i = block.first + r;
      const int yi = scene.labels[i];
      double* scores = residual.row(r).data();
      const TentPair* pairs = &scene.tents[std::size_t(i) * d];
      std::copy_n(w_t.row(row - 1).data(), k_count, scores);
      if (yi >= 0)
        for (int f = 0; f < d; ++f) {
          const double* lo = w_t.data() + std::size_t(pairs[f].column) * k_count;
          const double a = pairs[f].lower, c = pairs[f].upper;
          for (int k = 0; k < k_count; ++k) scores[k] += a * lo[k] + c * lo[k + k_count];
        }
      loss += softmax_residual(residual.row(r), yi);
      if (yi < 0) continue;
      for (int f = 0; f < d; ++f) {
        double* g = grad_t.data() + std::size_t(pairs[f].column) * k_count;
        const double a = pairs[f].lower, c = pairs[f].upper;
        for (int k = 0; k < k_count; ++k) {
          g[k] += a * scores[k];
          g[k + k_count] += c * scores[k];
        }
      }
      for (int k = 0; k < k_count; ++k) bias_grad[k] += scores[k];
    }
    return loss;
  }

  void evaluate_blocks_node_only(const Eigen::VectorXd& x) {
    const int k_count = shape_.classes;
    const int row = shape_.node_row();
    const Eigen::Map<const RowMatrixXd> w(x.data(), k_count, row);
    const RowMatrixXd w_t = w.transpose();  // a tent's K weights contiguous (tent_block)
    const long long block_count = static_cast<long long>(blocks_.size());
    struct Scratch {
      RowMatrixXd residual;  // p - [k == y_i] per node of the block (0 for ignored nodes)
      RowMatrixXd grad_t;    // node_row x K
    };
    parallel_for(
        block_count, threads_, Schedule::Dynamic(1), [] { return Scratch{}; },
        [&](Scratch& scratch, std::ptrdiff_t b) {
          RowMatrixXd& residual = scratch.residual;
          const NodeBlock& block = blocks_[b];
          const PreparedScene& scene = scenes_[block.scene];
          double loss = 0.0;
          Eigen::Map<RowMatrixXd> grad_w(partial_grad_.col(b).data(), k_count, row);
          if (scene.tents.empty()) {
            const auto features = scene.features.middleRows(block.first, block.count);
            residual.noalias() = features * w.transpose();
            for (long long r = 0; r < block.count; ++r)
              loss += softmax_residual(residual.row(r), scene.labels[block.first + r]);
            grad_w.noalias() = residual.transpose() * features;
          } else {
            loss = tent_block(block, w_t, residual, scratch.grad_t);
            grad_w = scratch.grad_t.transpose();
          }
          partial_loss_(b) = loss;
        });
  }

  void evaluate_blocks_with_edges(const Eigen::VectorXd& x) {
    const int k_count = shape_.classes;
    const int row = shape_.node_row();
    const int edge_row = shape_.edge_row();
    const int d = shape_.edge_dim;
    const Eigen::Map<const RowMatrixXd> w(x.data(), k_count, row);
    const Eigen::Map<const RowMatrixXd> v(x.data() + shape_.node_size(), k_count, edge_row);
    const long long block_count = static_cast<long long>(blocks_.size());
    struct Scratch {
      Eigen::VectorXd scores, prob;
      RowMatrixXd summed;        // A_i(k): edge features summed per neighbour label
      std::vector<int> present;  // labels among the neighbours
    };
    const auto make_scratch = [&] {
      Scratch scratch{
          Eigen::VectorXd(k_count), Eigen::VectorXd(k_count), RowMatrixXd(k_count, edge_row), {}};
      scratch.present.reserve(k_count);
      return scratch;
    };
    parallel_for(block_count, threads_, Schedule::Dynamic(1), make_scratch,
                 [&](Scratch& scratch, std::ptrdiff_t b) {
                   auto& [scores, prob, summed, present] = scratch;
                   const NodeBlock& block = blocks_[b];
                   const PreparedScene& scene = scenes_[block.scene];
                   const Graph& g = *scene.graph;
                   Eigen::Map<RowMatrixXd> grad_w(partial_grad_.col(b).data(), k_count, row);
                   Eigen::Map<RowMatrixXd> grad_v(partial_grad_.col(b).data() + shape_.node_size(),
                                                  k_count, edge_row);
                   double loss = 0.0;
                   for (long long i = block.first; i < block.first + block.count; ++i) {
                     const int yi = scene.labels[i];
                     if (yi < 0) continue;
                     const auto xi = scene.features.row(i);
                     const auto ui = scene.edge_features.row(i);
                     scores.noalias() = w * xi.transpose();
                     present.clear();
                     for (std::uint32_t j : g.neighbors_of(i)) {
                       const int yj = scene.labels[j];
                       if (yj < 0) continue;
                       if (std::find(present.begin(), present.end(), yj) == present.end()) {
                         present.push_back(yj);
                         summed.row(yj).setZero();
                       }
                       summed.row(yj).head(d) +=
                           ui.head(d).cwiseProduct(scene.edge_features.row(j).head(d));
                       summed(yj, d) += 1.0;
                     }
                     for (int l : present) scores(l) += v.row(l).dot(summed.row(l));
                     const double top = scores.maxCoeff();
                     prob = (scores.array() - top).exp();
                     const double z = prob.sum();
                     prob /= z;
                     const double weight = weights_[std::size_t(yi)];
                     loss -= weight * (scores(yi) - top - std::log(z));
                     prob(yi) -= 1.0;  // d(-log p(y_i)) / d score = p - [k == y_i]
                     prob *= weight;
                     grad_w.noalias() += prob * xi;
                     for (int l : present) grad_v.row(l) += prob(l) * summed.row(l);
                   }
                   partial_loss_(b) = loss;
                 });
  }

  const std::vector<PreparedScene>& scenes_;
  ParameterShape shape_;
  int threads_;
  std::vector<NodeBlock> blocks_;
  std::vector<double> weights_;   // per class index
  double labelled_ = 0.0;         // the weighted number of labelled points
  Eigen::MatrixXd partial_grad_;  // one column per block
  Eigen::VectorXd partial_loss_;
};

}  // namespace

std::unique_ptr<Objective> make_pseudo_likelihood(const std::vector<PreparedScene>& scenes,
                                                  const ParameterShape& shape, int threads,
                                                  std::vector<double> class_weights) {
  return std::make_unique<PseudoLikelihood>(scenes, shape, threads, std::move(class_weights));
}

}  // namespace primlabel::crf::detail
