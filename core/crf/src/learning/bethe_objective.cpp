// Log-likelihood with log Z approximated by minus the Bethe free energy at the loopy BP beliefs:
//   F = sum_(ij) sum_{k,l} mu_ij (log mu_ij - theta_ij - theta_i - theta_j)
//       - sum_i (deg_i - 1) sum_k mu_i (log mu_i - theta_i)
// With associative potentials mu_ij(k,l) = h_i(k) psi(k,l) h_j(l) / Z_ij (h = cavity beliefs,
// psi(k,l) = 1 for k != l), Z_ij = (sum h_i)(sum h_j) + sum_k h_i h_j (psi - 1), and the pairwise
// term collapses to O(K):  sum_k a_k (log h_i - theta_i) + sum_l c_l (log h_j - theta_j) - log
// Z_ij, a and c being the two marginals of mu_ij. At a BP fixed point d(-F)/d theta are the BP
// marginals, which give the gradient (exact on trees).

#include <cmath>
#include <limits>

#include "primlabel/geometry/parallel.hpp"
#include "learning/objectives.hpp"

namespace primlabel::crf::detail {
namespace {

// Sum of a_k * (log h_k - theta_k), skipping a_k == 0 (0 log 0 = 0).
double weighted_log_ratio(const Eigen::ArrayXd& a, const Eigen::ArrayXd& h, const double* theta) {
  double s = 0.0;
  for (Eigen::Index k = 0; k < a.size(); ++k)
    if (a(k) > 0.0) s += a(k) * (std::log(h(k)) - theta[k]);
  return s;
}

class BetheLikelihood final : public Objective {
 public:
  BetheLikelihood(const std::vector<PreparedScene>& scenes, const ParameterShape& shape,
                  const BpSettings& bp)
      : scenes_(scenes), shape_(shape), bp_(bp), blocks_(node_blocks(scenes)) {
    for (const auto& s : scenes_) {
      bps_.push_back(std::make_unique<LoopyBp>(*s.graph, shape.classes));
      for (int y : s.labels) labelled_ += y >= 0 ? 1 : 0;
    }
  }

  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) override {
    const int k_count = shape_.classes;
    const int row = shape_.node_row();
    const int edge_row = shape_.edge_row();
    const int d = shape_.edge_dim;
    const Eigen::Index half = shape_.node_size();
    const Eigen::Map<const RowMatrixXd> w(x.data(), k_count, row);
    const Eigen::Map<const RowMatrixXd> v(x.data() + half, k_count, edge_row);
    const int threads = bp_.threads;

    // Log-potentials in double; BP runs on their float images.
    std::vector<RowMatrixXd> node_theta(scenes_.size()), edge_theta(scenes_.size());
    std::vector<RowMatrixXd> beliefs(scenes_.size());
    for (std::size_t s = 0; s < scenes_.size(); ++s) {
      const PreparedScene& scene = scenes_[s];
      const Graph& g = *scene.graph;
      const long long n = static_cast<long long>(g.num_nodes());
      node_theta[s].resize(n, k_count);
      edge_theta[s].setZero(g.num_slots(), k_count);
      primlabel::detail::ExceptionBarrier barrier;
#pragma omp parallel num_threads(threads)
      {
        Eigen::RowVectorXd e(edge_row);
#pragma omp for schedule(dynamic, 256)
        for (long long i = 0; i < n; ++i)
          barrier.run([&] {
            node_theta[s].row(i).noalias() = scene.features.row(i) * w.transpose();
            for (std::uint32_t p = g.offsets[i]; p < g.offsets[i + 1]; ++p) {
              const std::uint32_t j = g.neighbors[p];
              if (j < i) continue;
              e.head(d) = scene.edge_features.row(i).head(d).cwiseProduct(
                  scene.edge_features.row(j).head(d));
              e(d) = 1.0;
              edge_theta[s].row(p).noalias() = e * v.transpose();
              edge_theta[s].row(g.reverse[p]) = edge_theta[s].row(p);
            }
          });
      }
      barrier.rethrow();
      RowMatrixXd phi(n, k_count);
#pragma omp parallel for schedule(static) num_threads(threads)
      for (long long i = 0; i < n; ++i)
        barrier.run([&] {
          phi.row(i) = (node_theta[s].row(i).array() - node_theta[s].row(i).maxCoeff()).exp();
        });
      barrier.rethrow();
      RowMatrixXf psi_minus_one = edge_theta[s].cast<float>();
      edge_scores_to_potentials_minus_one(psi_minus_one, threads);
      BpSettings settings = bp_;
      settings.max_product = false;
      saved_messages_ = bps_[s]->messages();
      last_run_ = bps_[s]->run(phi, psi_minus_one, settings);
      if (!last_run_.converged) {
        // Away from a BP fixed point the Bethe value and gradient are meaningless: report NaN so
        // the line search steps back, and keep the last converged messages for the next try.
        bps_[s]->set_messages(saved_messages_);
        gradient.setZero(x.size());
        return std::numeric_limits<double>::quiet_NaN();
      }
      beliefs[s] = bps_[s]->beliefs(phi, threads);
    }

    const long long block_count = static_cast<long long>(blocks_.size());
    partial_grad_.setZero(x.size(), block_count);
    partial_loss_.setZero(block_count);
    primlabel::detail::ExceptionBarrier barrier;
#pragma omp parallel num_threads(threads)
    {
      Eigen::ArrayXd hi(k_count), hj(k_count), a(k_count), c(k_count), psi_m1(k_count);
      Eigen::RowVectorXd e(edge_row);
#pragma omp for schedule(dynamic, 1)
      for (long long b = 0; b < block_count; ++b)
        barrier.run([&] {
          const NodeBlock& block = blocks_[b];
          const PreparedScene& scene = scenes_[block.scene];
          const Graph& g = *scene.graph;
          const RowMatrixXd& mu = beliefs[block.scene];
          const RowMatrixXd& theta = node_theta[block.scene];
          const RowMatrixXd& theta_e = edge_theta[block.scene];
          const LoopyBp& bp = *bps_[block.scene];
          Eigen::Map<RowMatrixXd> grad_w(partial_grad_.col(b).data(), k_count, row);
          Eigen::Map<RowMatrixXd> grad_v(partial_grad_.col(b).data() + half, k_count, edge_row);
          double loss = 0.0;  // -log-likelihood = -(empirical score) - F
          for (long long i = block.first; i < block.first + block.count; ++i) {
            const int yi = scene.labels[i];
            if (yi < 0) continue;  // ignored nodes are not in the graph
            const auto xi = scene.features.row(i);
            // Node: empirical score, expected features, and the -(deg - 1) node entropy term.
            loss -= theta(i, yi);
            grad_w.noalias() += mu.row(i).transpose() * xi;
            grad_w.row(yi) -= xi;
            const int deg = static_cast<int>(g.degree(i));
            double node_term = 0.0;
            for (int k = 0; k < k_count; ++k)
              if (mu(i, k) > 0.0) node_term += mu(i, k) * (std::log(mu(i, k)) - theta(i, k));
            loss += (deg - 1) * node_term;  // log Z ≈ -F, F has -(deg - 1) * node_term
            for (std::uint32_t p = g.offsets[i]; p < g.offsets[i + 1]; ++p) {
              const std::uint32_t j = g.neighbors[p];
              if (j < i) continue;  // each edge once
              const float* to_j = bp.message(p);
              const float* to_i = bp.message(g.reverse[p]);
              for (int k = 0; k < k_count; ++k) {
                hi(k) = mu(i, k) / to_i[k];
                hj(k) = mu(j, k) / to_j[k];
                psi_m1(k) = std::expm1(theta_e(p, k));
              }
              hi /= hi.maxCoeff();
              hj /= hj.maxCoeff();
              const double si = hi.sum(), sj = hj.sum();
              const double z = si * sj + (hi * hj * psi_m1).sum();
              a = hi * (sj + hj * psi_m1) / z;
              c = hj * (si + hi * psi_m1) / z;
              const double pair_term = weighted_log_ratio(a, hi, theta.row(i).data()) +
                                       weighted_log_ratio(c, hj, theta.row(j).data()) - std::log(z);
              loss -= pair_term;  // log Z ≈ -F, F has +pair_term
              const int yj = scene.labels[j];
              if (yi == yj) loss -= theta_e(p, yi);
              e.head(d) = scene.edge_features.row(i).head(d).cwiseProduct(
                  scene.edge_features.row(j).head(d));
              e(d) = 1.0;
              for (int k = 0; k < k_count; ++k) {
                const double mu_kk = hi(k) * (psi_m1(k) + 1.0) * hj(k) / z;
                grad_v.row(k) += (mu_kk - (yi == k && yj == k ? 1.0 : 0.0)) * e;
              }
            }
          }
          partial_loss_(b) = loss;
        });
    }
    barrier.rethrow();
    return sum_blocks(partial_grad_, partial_loss_, labelled_, gradient);
  }

 private:
  const std::vector<PreparedScene>& scenes_;
  ParameterShape shape_;
  BpSettings bp_;
  std::vector<NodeBlock> blocks_;
  std::vector<std::unique_ptr<LoopyBp>> bps_;  // per scene, kept for warm starts
  std::size_t labelled_ = 0;
  BpRun last_run_;
  std::vector<float> saved_messages_;
  Eigen::MatrixXd partial_grad_;
  Eigen::VectorXd partial_loss_;
};

}  // namespace

std::unique_ptr<Objective> make_bethe(const std::vector<PreparedScene>& scenes,
                                      const ParameterShape& shape, const BpSettings& bp) {
  return std::make_unique<BetheLikelihood>(scenes, shape, bp);
}

}  // namespace primlabel::crf::detail
