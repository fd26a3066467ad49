#include "loopy_bp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace primlabel::crf::detail {
namespace {

// Products of more than this many messages are rescaled, so a belief never underflows double.
constexpr int kRescaleEvery = 16;
// psi = exp(theta) stays far from float overflow (messages are products of psi and values <= 1).
constexpr float kMaxEdgeScore = 60.0f;

void scale_to_max_one(double* v, int k_count) {
  double mx = 0.0;
  for (int k = 0; k < k_count; ++k) mx = std::max(mx, v[k]);
  if (mx > 0.0) {
    const double inv = 1.0 / mx;
    for (int k = 0; k < k_count; ++k) v[k] *= inv;
  }
}

// b(k) = phi_i(k) prod_{j in N(i)} m_{j->i}(k), up to a positive factor.
void node_product(const Graph& graph, std::size_t i, const double* phi_row, const float* messages,
                  int k_count, double* b) {
  std::copy_n(phi_row, k_count, b);
  int since_rescale = 0;
  for (std::uint32_t q = graph.offsets[i]; q < graph.offsets[i + 1]; ++q) {
    const float* in = messages + std::size_t(graph.reverse[q]) * k_count;
    for (int k = 0; k < k_count; ++k) b[k] *= in[k];
    if (++since_rescale == kRescaleEvery) {
      scale_to_max_one(b, k_count);
      since_rescale = 0;
    }
  }
}

}  // namespace

RowMatrixXd node_potentials(const RowMatrixXf& node_scores, int threads) {
  RowMatrixXd phi(node_scores.rows(), node_scores.cols());
  const long long n = node_scores.rows();
#pragma omp parallel for schedule(static) num_threads(threads)
  for (long long i = 0; i < n; ++i) {
    const float mx = node_scores.row(i).maxCoeff();
    phi.row(i) = (node_scores.row(i).array() - mx).cast<double>().exp();
  }
  return phi;
}

void edge_scores_to_potentials_minus_one(RowMatrixXf& edge_scores, int threads) {
  // One flat, vectorised exp over fixed chunks (rows of K are too short to vectorise well).
  constexpr Eigen::Index kChunk = 1 << 14;
  const Eigen::Index total = edge_scores.size();
  const long long chunks = static_cast<long long>((total + kChunk - 1) / kChunk);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (long long c = 0; c < chunks; ++c) {
    const Eigen::Index first = c * kChunk;
    const Eigen::Index count = std::min(kChunk, total - first);
    Eigen::Map<Eigen::ArrayXf> chunk(edge_scores.data() + first, count);
    chunk = chunk.min(kMaxEdgeScore).exp() - 1.0f;
  }
}

LoopyBp::LoopyBp(const Graph& graph, int num_classes)
    : graph_(graph),
      num_classes_(num_classes),
      messages_(graph.num_slots() * num_classes, 1.0f),
      next_(graph.num_slots() * num_classes, 1.0f) {
  if (num_classes < 1 || num_classes > kMaxBpClasses)
    throw std::invalid_argument("loopy BP: the number of classes must be in [1, " +
                                std::to_string(kMaxBpClasses) + "]");
}

void LoopyBp::reset() { std::fill(messages_.begin(), messages_.end(), 1.0f); }

namespace {

struct UpdateContext {
  const Graph& graph;
  const RowMatrixXd& phi;
  const RowMatrixXf& psi_minus_one;
  const float* old_messages;
  float* new_messages;
  float keep;  // damping
  bool max_product;
};

// Computes the new messages of one node at a time. KC is the class count when known at compile
// time (Eigen then unrolls and vectorises the fixed-size arrays) or Eigen::Dynamic.
template <int KC>
class NodeUpdater {
  using ArrayF = Eigen::Array<float, KC, 1>;
  using ArrayD = Eigen::Array<double, KC, 1>;
  using ConstMapF = Eigen::Map<const ArrayF>;
  using ConstMapD = Eigen::Map<const ArrayD>;

 public:
  explicit NodeUpdater(int k_count)
      : k_(k_count), b_(k_count), bf_(k_count), h_(k_count), msg_(k_count) {}

  // Writes the messages from node i to all its neighbours; returns the largest change.
  float update(const UpdateContext& c, std::size_t i) {
    const Graph& g = c.graph;
    // b = phi_i * prod of incoming messages, in double (up to ~20 factors >= 1e-30 each).
    b_ = ConstMapD(c.phi.row(i).data(), k_);
    int since_rescale = 0;
    for (std::uint32_t q = g.offsets[i]; q < g.offsets[i + 1]; ++q) {
      b_ *= ConstMapF(c.old_messages + std::size_t(g.reverse[q]) * k_, k_).template cast<double>();
      if (++since_rescale == kRescaleEvery) {
        rescale(b_);
        since_rescale = 0;
      }
    }
    const double b_max = b_.maxCoeff();
    // Scaled to max 1, float keeps everything that matters next to the maximum.
    if (b_max > 0.0 && std::isfinite(b_max))
      bf_ = (b_ * (1.0 / b_max)).template cast<float>();
    else
      bf_.setOnes();  // degenerate (all-zero) product: send uninformative messages
    const float take = 1.0f - c.keep;
    float max_change = 0.0f;
    for (std::uint32_t p = g.offsets[i]; p < g.offsets[i + 1]; ++p) {
      // Cavity: the belief without the message that came from the receiver, scaled to max 1.
      h_ = bf_ / ConstMapF(c.old_messages + std::size_t(g.reverse[p]) * k_, k_);
      h_ *= 1.0f / h_.maxCoeff();
      const ConstMapF pm1(c.psi_minus_one.data() + std::size_t(p) * k_, k_);
      if (!c.max_product) {
        msg_ = h_.sum() + h_ * pm1;
      } else {
        Eigen::Index best = 0;
        h_.maxCoeff(&best);  // = 1 after scaling
        const float saved = h_(best);
        h_(best) = -1.0f;
        const float second = h_.maxCoeff();
        h_(best) = saved;
        msg_ = h_ * (pm1 + 1.0f);
        msg_ = msg_.max(1.0f);  // the best label k != l has h = 1 for every l but `best`
        msg_(best) = std::max(second, h_(best) * (pm1(best) + 1.0f));
      }
      float m = msg_.maxCoeff();
      if (!(m > 0.0f && m < std::numeric_limits<float>::infinity())) {
        msg_.setOnes();
        m = 1.0f;
      }
      const ConstMapF old(c.old_messages + std::size_t(p) * k_, k_);
      Eigen::Map<ArrayF> out(c.new_messages + std::size_t(p) * k_, k_);
      out = take * (msg_ * (1.0f / m)).max(kMessageFloor) + c.keep * old;
      max_change = std::max(max_change, (out - old).abs().maxCoeff());
    }
    return max_change;
  }

 private:
  static void rescale(ArrayD& v) {
    const double mx = v.maxCoeff();
    if (mx > 0.0 && std::isfinite(mx)) v *= 1.0 / mx;
  }

  int k_;
  ArrayD b_;
  ArrayF bf_, h_, msg_;
};

// Products of tiny values would otherwise run into subnormals, which are ~100x slower on x86;
// flushing them to zero changes nothing that matters next to a maximum of 1.
class FlushSubnormals {
 public:
  FlushSubnormals() {
#if defined(__SSE2__)
    saved_ = _mm_getcsr();
    _mm_setcsr(saved_ | 0x8040);  // FTZ | DAZ
#endif
  }
  ~FlushSubnormals() {
#if defined(__SSE2__)
    _mm_setcsr(saved_);
#endif
  }
  FlushSubnormals(const FlushSubnormals&) = delete;
  FlushSubnormals& operator=(const FlushSubnormals&) = delete;

 private:
  unsigned saved_ = 0;
};

template <int KC>
float update_all(const UpdateContext& c, int k_count, int threads) {
  const long long n = static_cast<long long>(c.graph.num_nodes());
  float max_change = 0.0f;
#pragma omp parallel num_threads(threads) reduction(max : max_change)
  {
    FlushSubnormals flush;
    NodeUpdater<KC> updater(k_count);
#pragma omp for schedule(dynamic, 512)
    for (long long i = 0; i < n; ++i) {
      if (c.graph.offsets[i] == c.graph.offsets[i + 1]) continue;
      max_change = std::max(max_change, updater.update(c, i));
    }
  }
  return max_change;
}

float update_all_dispatch(const UpdateContext& c, int k_count, int threads) {
  switch (k_count) {
    case 2:
      return update_all<2>(c, k_count, threads);
    case 3:
      return update_all<3>(c, k_count, threads);
    case 4:
      return update_all<4>(c, k_count, threads);
    case 5:
      return update_all<5>(c, k_count, threads);
    case 6:
      return update_all<6>(c, k_count, threads);
    case 7:
      return update_all<7>(c, k_count, threads);
    case 8:
      return update_all<8>(c, k_count, threads);
    case 9:
      return update_all<9>(c, k_count, threads);
    case 10:
      return update_all<10>(c, k_count, threads);
    case 11:
      return update_all<11>(c, k_count, threads);
    case 12:
      return update_all<12>(c, k_count, threads);
    default:
      return update_all<Eigen::Dynamic>(c, k_count, threads);
  }
}

}  // namespace

BpRun LoopyBp::run(const RowMatrixXd& phi, const RowMatrixXf& psi_minus_one,
                   const BpSettings& settings) {
  BpRun report;
  for (int iteration = 1; iteration <= settings.max_iterations; ++iteration) {
    const UpdateContext context{graph_,
                                phi,
                                psi_minus_one,
                                messages_.data(),
                                next_.data(),
                                settings.damping,
                                settings.max_product};
    const float max_change = update_all_dispatch(context, num_classes_, settings.threads);
    messages_.swap(next_);
    report.iterations = iteration;
    report.final_change = max_change;
    if (max_change < settings.tolerance) {
      report.converged = true;
      break;
    }
  }
  return report;
}

RowMatrixXd LoopyBp::beliefs(const RowMatrixXd& phi, int threads) const {
  const int k_count = num_classes_;
  const long long n = static_cast<long long>(graph_.num_nodes());
  RowMatrixXd out = RowMatrixXd::Zero(n, k_count);
#pragma omp parallel for schedule(dynamic, 512) num_threads(threads)
  for (long long i = 0; i < n; ++i) {
    if (!graph_.active[i]) continue;
    double* b = out.row(i).data();
    node_product(graph_, i, phi.row(i).data(), messages_.data(), k_count, b);
    double sum = 0.0;
    for (int k = 0; k < k_count; ++k) sum += b[k];
    if (sum > 0.0 && std::isfinite(sum)) {
      for (int k = 0; k < k_count; ++k) b[k] /= sum;
    } else {
      for (int k = 0; k < k_count; ++k) b[k] = 1.0 / k_count;
    }
  }
  return out;
}

}  // namespace primlabel::crf::detail
