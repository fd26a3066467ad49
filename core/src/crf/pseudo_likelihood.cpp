// Pseudo-likelihood  sum_i log p(y_i | y_N(i), x)  and, without edges, logistic regression.
//
// p(y_i = k | y_N(i)) ∝ exp(w_k . x_i + sum_{j in N(i), y_j = k} v_k . e_ij): only neighbours
// labelled k contribute to class k, so per node the edge features are summed per neighbour label
// (A_i(k) = sum_{j: y_j = k} e_ij) and each class costs one dot product.

#include <algorithm>
#include <cmath>

#include "objectives.hpp"

namespace primlabel::crf::detail {
namespace {

class PseudoLikelihood final : public Objective {
 public:
  PseudoLikelihood(const std::vector<PreparedScene>& scenes, const ParameterShape& shape,
                   int threads)
      : scenes_(scenes), shape_(shape), threads_(threads), blocks_(node_blocks(scenes)) {
    for (const auto& s : scenes_)
      for (int y : s.labels) labelled_ += y >= 0 ? 1 : 0;
  }

  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) override {
    const int k_count = shape_.classes;
    const int row = shape_.row();
    const int d = shape_.dim;
    const Eigen::Index half = Eigen::Index(k_count) * row;
    const Eigen::Map<const RowMatrixXd> w(x.data(), k_count, row);
    const Eigen::Map<const RowMatrixXd> v(x.data() + (shape_.edges ? half : 0), k_count, row);
    const long long block_count = static_cast<long long>(blocks_.size());
    partial_grad_.setZero(x.size(), block_count);
    partial_loss_.setZero(block_count);

#pragma omp parallel num_threads(threads_)
    {
      Eigen::VectorXd scores(k_count), prob(k_count);
      RowMatrixXd summed(k_count, row);  // A_i(k): edge features summed per neighbour label
      std::vector<int> present;          // labels among the neighbours
      present.reserve(k_count);
#pragma omp for schedule(dynamic, 1)
      for (long long b = 0; b < block_count; ++b) {
        const NodeBlock& block = blocks_[b];
        const PreparedScene& scene = scenes_[block.scene];
        const Graph& g = *scene.graph;
        Eigen::Map<RowMatrixXd> grad_w(partial_grad_.col(b).data(), k_count, row);
        Eigen::Map<RowMatrixXd> grad_v(partial_grad_.col(b).data() + (shape_.edges ? half : 0),
                                       k_count, row);
        double loss = 0.0;
        for (long long i = block.first; i < block.first + block.count; ++i) {
          const int yi = scene.labels[i];
          if (yi < 0) continue;
          const auto xi = scene.features.row(i);
          scores.noalias() = w * xi.transpose();
          present.clear();
          if (shape_.edges) {
            for (std::uint32_t j : g.neighbors_of(i)) {
              const int yj = scene.labels[j];
              if (yj < 0) continue;
              if (std::find(present.begin(), present.end(), yj) == present.end()) {
                present.push_back(yj);
                summed.row(yj).setZero();
              }
              summed.row(yj).head(d) += xi.head(d).cwiseProduct(scene.features.row(j).head(d));
              summed(yj, d) += 1.0;
            }
            for (int l : present) scores(l) += v.row(l).dot(summed.row(l));
          }
          const double top = scores.maxCoeff();
          prob = (scores.array() - top).exp();
          const double z = prob.sum();
          prob /= z;
          loss -= scores(yi) - top - std::log(z);
          prob(yi) -= 1.0;  // d(-log p(y_i)) / d score = p - [k == y_i]
          grad_w.noalias() += prob * xi;
          for (int l : present) grad_v.row(l) += prob(l) * summed.row(l);
        }
        partial_loss_(b) = loss;
      }
    }
    // Block order, not thread order: identical for any thread count.
    gradient.setZero(x.size());
    double loss = 0.0;
    for (long long b = 0; b < block_count; ++b) {
      gradient += partial_grad_.col(b);
      loss += partial_loss_(b);
    }
    const double scale = labelled_ > 0 ? 1.0 / double(labelled_) : 0.0;
    gradient *= scale;
    return loss * scale;
  }

 private:
  const std::vector<PreparedScene>& scenes_;
  ParameterShape shape_;
  int threads_;
  std::vector<NodeBlock> blocks_;
  std::size_t labelled_ = 0;
  Eigen::MatrixXd partial_grad_;  // one column per block
  Eigen::VectorXd partial_loss_;
};

}  // namespace

std::unique_ptr<Objective> make_pseudo_likelihood(const std::vector<PreparedScene>& scenes,
                                                  const ParameterShape& shape, int threads) {
  return std::make_unique<PseudoLikelihood>(scenes, shape, threads);
}

}  // namespace primlabel::crf::detail
