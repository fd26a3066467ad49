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
#include <memory>
#include <span>

#include "learning/objectives.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel::crf::detail {

using primlabel::detail::parallel_for;
using primlabel::detail::Schedule;

namespace {

// theta is capped before exp, as in inference (potentials.cpp): psi stays far from float overflow.
constexpr double kMaxEdgeScore = 60.0;

// Sum of a_k * (log h_k - theta_k), skipping a_k == 0 (0 log 0 = 0).
double weighted_log_ratio(const Eigen::ArrayXd& a, const Eigen::ArrayXd& h, const double* theta) {
  double s = 0.0;
  for (Eigen::Index k = 0; k < a.size(); ++k)
    if (a(k) > 0.0) s += a(k) * (std::log(h(k)) - theta[k]);
  return s;
}

// One scene's BP state, kept between evaluations for warm starts.
struct SceneBp {
  BeliefPropagation bp;
  ScratchBuffer<std::uint32_t> edge_of, block_first_edge;  // fixed: the graph does not change
  ScratchBuffer<float> phi, psi_minus_one;                 // padded, from the current parameters
  std::vector<float> saved;                                // the last converged messages
};

class BetheLikelihood final : public Objective {
 public:
  BetheLikelihood(const std::vector<PreparedScene>& scenes, const ParameterShape& shape,
                  const BpSettings& bp, const RunContext& context)
      : scenes_(scenes), shape_(shape), bp_(bp), context_(context), blocks_(node_blocks(scenes)) {
    bp_.max_product = false;
    bp_.fixed_point = true;
    for (const auto& s : scenes_) {
      auto state = std::make_unique<SceneBp>();
      number_edges(*s.graph, context_.threads, state->edge_of, state->block_first_edge,
                   context_.stop);
      bps_.push_back(std::move(state));
      for (int y : s.labels) labelled_ += y >= 0 ? 1 : 0;
    }
  }

  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) override {
    const int k_count = shape_.classes;
    const int kp = padded_classes(k_count);
    const int row = shape_.node_row();
    const int edge_row = shape_.edge_row();
    const int d = shape_.edge_dim;
    const Eigen::Index half = shape_.node_size();
    const Eigen::Map<const RowMatrixXd> w(x.data(), k_count, row);
    const Eigen::Map<const RowMatrixXd> v(x.data() + half, k_count, edge_row);
    const int threads = context_.threads;

    // Log-potentials in double; BP runs on their float images, in the layout inference uses.
    std::vector<RowMatrixXd> node_theta(scenes_.size()), edge_theta(scenes_.size());
    std::vector<RowMatrixXd> beliefs(scenes_.size());
    for (std::size_t s = 0; s < scenes_.size(); ++s) {
      const PreparedScene& scene = scenes_[s];
      const Graph& g = *scene.graph;
      SceneBp& state = *bps_[s];
      const long long n = static_cast<long long>(g.num_nodes());
      node_theta[s].resize(n, k_count);
      edge_theta[s].setZero(g.num_slots(), k_count);
      float* phi = state.phi.resize(std::size_t(n) * kp);
      float* psi = state.psi_minus_one.resize(g.num_edges() * kp);
      const std::uint32_t* edge_of = state.edge_of.data();
      parallel_for(
          n, threads, Schedule::Dynamic(256), [&] { return Eigen::RowVectorXd(edge_row); },
          [&](Eigen::RowVectorXd& e, std::ptrdiff_t i) {
            node_theta[s].row(i).noalias() = scene.features.row(i) * w.transpose();
            const auto theta = node_theta[s].row(i);
            const double mx = theta.maxCoeff();
            for (int k = 0; k < kp; ++k)
              phi[i * kp + k] = k < k_count ? static_cast<float>(std::exp(theta(k) - mx)) : 0.0f;
            for (std::uint32_t p = g.offsets[i]; p < g.offsets[i + 1]; ++p) {
              const std::uint32_t j = g.neighbors[p];
              if (j < i) continue;
              e.head(d) = scene.edge_features.row(i).head(d).cwiseProduct(
                  scene.edge_features.row(j).head(d));
              e(d) = 1.0;
              edge_theta[s].row(p).noalias() = e * v.transpose();
              edge_theta[s].row(g.reverse[p]) = edge_theta[s].row(p);
              // psi - 1, with theta capped as inference caps it (far from float overflow).
              float* out = psi + std::size_t(edge_of[p]) * kp;
              for (int k = 0; k < kp; ++k)
                out[k] = k < k_count ? static_cast<float>(
                                           std::expm1(std::min(edge_theta[s](p, k), kMaxEdgeScore)))
                                     : 0.0f;
            }
          });
      const BpPotentials potentials{&g, k_count, phi, psi, edge_of};
      state.bp.set_potentials(potentials);  // a warm start once a run has converged
      const BpRun run = state.bp.run(bp_, context_);
      context_.throw_if_stopped("Bethe training");
      if (!run.converged) {
        // Away from a BP fixed point the Bethe value and gradient are meaningless: report NaN so
        // the line search steps back, and keep the last converged messages for the next try.
        if (state.saved.empty()) {
          state.bp.reset(potentials);
        } else {
          state.bp.set_messages(state.saved);
        }
        gradient.setZero(x.size());
        return std::numeric_limits<double>::quiet_NaN();
      }
      const std::span<const float> messages = state.bp.messages();
      state.saved.assign(messages.begin(), messages.end());
      beliefs[s] = RowMatrixXd::Zero(n, k_count);
      parallel_for(n, threads, Schedule::Static(), [&](std::ptrdiff_t i) {
        if (g.active[i]) state.bp.beliefs(i, {beliefs[s].row(i).data(), std::size_t(k_count)});
      });
    }

    const auto block_count = static_cast<std::ptrdiff_t>(blocks_.size());
    partial_grad_.setZero(x.size(), block_count);
    partial_loss_.setZero(block_count);
    struct Scratch {
      Eigen::ArrayXd hi, hj, a, c, psi_m1;
      Eigen::RowVectorXd e;
    };
    const auto make_scratch = [&] {
      const Eigen::ArrayXd k_values(k_count);
      return Scratch{k_values, k_values, k_values,
                     k_values, k_values, Eigen::RowVectorXd(edge_row)};
    };
    primlabel::detail::for_each_block(
        block_count, context_, make_scratch, [&](Scratch& scratch, std::ptrdiff_t b) {
          auto& [hi, hj, a, c, psi_m1, e] = scratch;
          const NodeBlock& block = blocks_[b];
          const PreparedScene& scene = scenes_[block.scene];
          const Graph& g = *scene.graph;
          const RowMatrixXd& mu = beliefs[block.scene];
          const RowMatrixXd& theta = node_theta[block.scene];
          const RowMatrixXd& theta_e = edge_theta[block.scene];
          const BeliefPropagation& bp = bps_[block.scene]->bp;
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
    context_.throw_if_stopped("Bethe training");
    return sum_blocks(partial_grad_, partial_loss_, double(labelled_), gradient);
  }

 private:
  const std::vector<PreparedScene>& scenes_;
  ParameterShape shape_;
  BpSettings bp_;
  RunContext context_;
  std::vector<NodeBlock> blocks_;
  std::vector<std::unique_ptr<SceneBp>> bps_;  // per scene, kept for warm starts
  std::size_t labelled_ = 0;
  Eigen::MatrixXd partial_grad_;
  Eigen::VectorXd partial_loss_;
};

}  // namespace

std::unique_ptr<Objective> make_bethe(const std::vector<PreparedScene>& scenes,
                                      const ParameterShape& shape, const BpSettings& bp,
                                      const RunContext& context) {
  return std::make_unique<BetheLikelihood>(scenes, shape, bp, context);
}

}  // namespace primlabel::crf::detail
