#include "inference/loopy_bp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "primlabel/geometry/parallel.hpp"

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
  primlabel::detail::ExceptionBarrier barrier;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (long long i = 0; i < n; ++i)
    barrier.run([&] {
      const float mx = node_scores.row(i).maxCoeff();
      phi.row(i) = (node_scores.row(i).array() - mx).cast<double>().exp();
    });
  barrier.rethrow();
  return phi;
}

void edge_scores_to_potentials_minus_one(RowMatrixXf& edge_scores, int threads) {
  // One flat, vectorised exp over fixed chunks (rows of K are too short to vectorise well).
  constexpr Eigen::Index kChunk = 1 << 14;
  const Eigen::Index total = edge_scores.size();
  const long long chunks = static_cast<long long>((total + kChunk - 1) / kChunk);
  primlabel::detail::ExceptionBarrier barrier;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (long long c = 0; c < chunks; ++c)
    barrier.run([&] {
      const Eigen::Index first = c * kChunk;
      const Eigen::Index count = std::min(kChunk, total - first);
      Eigen::Map<Eigen::ArrayXf> chunk(edge_scores.data() + first, count);
      chunk = chunk.min(kMaxEdgeScore).exp() - 1.0f;
    });
  barrier.rethrow();
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

template <int KC>
float update_all(const UpdateContext& c, int k_count, int threads) {
  const long long n = static_cast<long long>(c.graph.num_nodes());
  float max_change = 0.0f;
  primlabel::detail::ExceptionBarrier barrier;
#pragma omp parallel num_threads(threads) reduction(max : max_change)
  {
    FlushSubnormals flush;
    NodeUpdater<KC> updater(k_count);
#pragma omp for schedule(dynamic, 512)
    for (long long i = 0; i < n; ++i)
      barrier.run([&] {
        if (c.graph.offsets[i] == c.graph.offsets[i + 1]) return;
        max_change = std::max(max_change, updater.update(c, i));
      });
  }
  barrier.rethrow();
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
    if (report.record(iteration, max_change, settings.tolerance)) break;
  }
  return report;
}

RowMatrixXd LoopyBp::beliefs(const RowMatrixXd& phi, int threads) const {
  const int k_count = num_classes_;
  const long long n = static_cast<long long>(graph_.num_nodes());
  RowMatrixXd out = RowMatrixXd::Zero(n, k_count);
  primlabel::detail::ExceptionBarrier barrier;
#pragma omp parallel for schedule(dynamic, 512) num_threads(threads)
  for (long long i = 0; i < n; ++i)
    barrier.run([&] {
      if (!graph_.active[i]) return;
      double* b = out.row(i).data();
      node_product(graph_, i, phi.row(i).data(), messages_.data(), k_count, b);
      double sum = 0.0;
      for (int k = 0; k < k_count; ++k) sum += b[k];
      if (sum > 0.0 && std::isfinite(sum)) {
        for (int k = 0; k < k_count; ++k) b[k] /= sum;
      } else {
        for (int k = 0; k < k_count; ++k) b[k] = 1.0 / k_count;
      }
    });
  barrier.rethrow();
  return out;
}

}  // namespace primlabel::crf::detail

// ---- Inference fast path -----------------------------------------------------------------------

namespace primlabel::crf::detail {
namespace {

// One node's update on the padded layout. KP is the padded class count when known at compile
// time (Eigen then keeps whole rows in SSE registers) or Eigen::Dynamic.
template <int KP>
class FastNodeUpdater {
  using ArrayF = Eigen::Array<float, KP, 1>;
  using ArrayD = Eigen::Array<double, KP, 1>;
  using MapF = Eigen::Map<ArrayF>;
  using ConstMapF = Eigen::Map<const ArrayF>;

 public:
  FastNodeUpdater(int k_count, int kp)
      : k_(k_count), kp_(kp), b_(kp), bf_(kp), h_(kp), msg_(kp), ones_(kp), real_(kp), pad_(kp) {
    ones_.setOnes();
    for (int k = 0; k < kp; ++k) {
      real_(k) = k < k_count ? 1.0f : 0.0f;
      pad_(k) = 1.0f - real_(k);
    }
    units_.assign(std::size_t(kp) * kp, 0.0f);
    for (int k = 0; k < kp; ++k) units_[std::size_t(k) * kp + k] = 1.0f;
  }

  // Writes node i's outgoing messages into `next` and its belief into `beliefs`; returns how far
  // the belief moved since the previous iteration (0 on the first one, which reads no message:
  // they all start at 1). `message_change` gets the largest change of an outgoing message.
  float update(float& message_change, const Graph& g, const FastBpProblem& pr, const float* old,
               float* next, float* beliefs, bool first, float keep, bool max_product,
               std::size_t i) {
    const std::uint32_t begin = g.offsets[i], end = g.offsets[i + 1];
    // b = phi_i * prod of incoming messages, in double (up to ~20 factors >= 1e-30 each).
    b_ = ConstMapF(pr.phi + i * kp_, kp_).template cast<double>();
    if (!first) {
      int since_rescale = 0;
      for (std::uint32_t q = begin; q < end; ++q) {
        b_ *= ConstMapF(old + std::size_t(g.reverse[q]) * kp_, kp_).template cast<double>();
        if (++since_rescale == kRescaleEvery) {
          const double mx = b_.maxCoeff();
          if (mx > 0.0 && std::isfinite(mx)) b_ *= 1.0 / mx;
          since_rescale = 0;
        }
      }
    }
    const double b_max = b_.maxCoeff();
    if (b_max > 0.0 && std::isfinite(b_max)) {
      bf_ = (b_ * (1.0 / b_max)).template cast<float>();
    } else {
      bf_ = real_;  // degenerate (all-zero) product: send uninformative messages
    }
    // The belief as inference returns it (sum 1), to test convergence.
    MapF belief(beliefs + i * kp_, kp_);
    const ArrayF normalised = bf_ * (1.0f / bf_.sum());
    const float change = first ? 0.0f : (normalised - belief).abs().maxCoeff();
    belief = normalised;

    const float take = 1.0f - keep;
    ArrayF moved = ArrayF::Zero(kp_);
    for (std::uint32_t p = begin; p < end; ++p) {
      // Cavity: the belief without the message that came from the receiver, scaled to max 1.
      const float* in = first ? ones_.data() : old + std::size_t(g.reverse[p]) * kp_;
      if (first) {
        h_ = bf_;  // every incoming message is 1
      } else {
        h_ = bf_ / ConstMapF(in, kp_);
      }
      // Sum-product messages are homogeneous in h: scaling h to sum 1 (instead of max 1) keeps
      // h psi in range and saves a reduction; max-product needs the maximum anyway.
      const float h_scale = max_product ? h_.maxCoeff() : h_.sum();
      MapF out(next + std::size_t(p) * kp_, kp_);
      const ConstMapF previous(first ? ones_.data() : old + std::size_t(p) * kp_, kp_);
      if (!(h_scale > 0.0f && h_scale < std::numeric_limits<float>::infinity())) {
        msg_ = take * ones_ + keep * previous;
        out = msg_;
        moved = moved.max((msg_ - previous).abs());
        continue;
      }
      h_ *= 1.0f / h_scale;
      const ConstMapF pm1(pr.psi_minus_one + std::size_t(pr.edge_of[p]) * kp_, kp_);
      if (!max_product) {
        msg_ = 1.0f + h_ * pm1;  // S + h (psi - 1) with S = 1
      } else {
        // best = first maximum of h (= 1 after scaling), second = the largest other value.
        int best = 0;
        float top = -1.0f, second = -1.0f;
        for (int k = 0; k < kp_; ++k) {
          const float v = h_(k);
          if (v > top) {
            second = top;
            top = v;
            best = k;
          } else if (v > second) {
            second = v;
          }
        }
        // m(l) = max(max_{k != l} h(k), h(l) psi(l)): the first term is 1 for every l but
        // `best`, where it is `second`. Built from a unit vector, as scalar stores into msg_
        // would stall the vector loads that follow.
        msg_ = (h_ * (pm1 + 1.0f)).max(ones_ - (1.0f - second) * unit(best));
      }
      float m = msg_.maxCoeff();
      if (!(m > 0.0f && m < std::numeric_limits<float>::infinity())) {
        msg_.setOnes();
        m = 1.0f;
      }
      // Pads stay 1 (so cavities keep pads 0), set in registers: scalar stores into `out` would
      // stall the vector loads that follow.
      msg_ = (take * (msg_ * (1.0f / m)).max(kMessageFloor) + keep * previous) * real_ + pad_;
      out = msg_;
      moved = moved.max((msg_ - previous).abs());
    }
    message_change = moved.maxCoeff();
    return change;
  }

 private:
  int k_, kp_;
  ArrayD b_;
  ArrayF bf_, h_, msg_, ones_;
  ArrayF real_, pad_;         // 1 on the K real classes / on the pads
  std::vector<float> units_;  // kp unit vectors

  ConstMapF unit(int k) const { return ConstMapF(units_.data() + std::size_t(k) * kp_, kp_); }
};

// What one synchronous iteration reads and writes.
struct FastIteration {
  const FastBpProblem& pr;
  const float* old;
  float* next;
  float* beliefs;
  const std::uint8_t* moved_before;  // per node: its messages moved >= tolerance last iteration
  std::uint8_t* moved;               // ... this iteration
  std::uint8_t* same;                // per node: its messages are equal in both buffers
  bool first;
  float keep;
  float tolerance;
  bool max_product;
  const std::stop_token& stop;
};

template <int KP>
float fast_update_all(const FastIteration& it, int threads) {
  const Graph& g = *it.pr.graph;
  const long long n = static_cast<long long>(g.num_nodes());
  const int kp = padded_classes(it.pr.classes);
  float max_change = 0.0f;
  primlabel::detail::ExceptionBarrier barrier;
#pragma omp parallel num_threads(threads) reduction(max : max_change)
  {
    FlushSubnormals flush;
    FastNodeUpdater<KP> updater(it.pr.classes, kp);
    bool stopped = false;  // per thread: once cancelled, the remaining nodes are skipped
#pragma omp for schedule(dynamic, 1024)
    for (long long i = 0; i < n; ++i)
      barrier.run([&] {
        if ((i & 1023) == 0) stopped = stopped || it.stop.stop_requested();
        if (stopped) return;
        const std::uint32_t begin = g.offsets[i], end = g.offsets[i + 1];
        if (begin == end) return;
        // A node whose messages and inputs all settled (moved < tolerance last iteration) would
        // only repeat itself: skip it. Decided from the previous iteration alone, so the result
        // still does not depend on the thread count.
        bool needed = it.first || it.moved_before[i];
        for (std::uint32_t p = begin; !needed && p < end; ++p)
          needed = it.moved_before[g.neighbors[p]] != 0;
        if (!needed) {
          if (!it.same[i]) {
            std::copy(it.old + std::size_t(begin) * kp, it.old + std::size_t(end) * kp,
                      it.next + std::size_t(begin) * kp);
            it.same[i] = 1;
          }
          it.moved[i] = 0;
          return;
        }
        it.same[i] = 0;
        float message_change = 0.0f;
        const float change = updater.update(message_change, g, it.pr, it.old, it.next, it.beliefs,
                                            it.first, it.keep, it.max_product, i);
        it.moved[i] = message_change >= it.tolerance;
        max_change = std::max(max_change, change);
      });
  }
  barrier.rethrow();
  return max_change;
}

float fast_update_dispatch(const FastIteration& it, int threads) {
  switch (padded_classes(it.pr.classes)) {
    case 4:
      return fast_update_all<4>(it, threads);
    case 8:
      return fast_update_all<8>(it, threads);
    case 12:
      return fast_update_all<12>(it, threads);
    case 16:
      return fast_update_all<16>(it, threads);
    default:
      return fast_update_all<Eigen::Dynamic>(it, threads);
  }
}

}  // namespace

BpRun run_fast_bp(const FastBpProblem& problem, const BpSettings& settings,
                  FastBpBuffers& buffers) {
  if (problem.classes < 1 || problem.classes > kMaxBpClasses)
    throw std::invalid_argument("loopy BP: the number of classes must be in [1, " +
                                std::to_string(kMaxBpClasses) + "]");
  const Graph& g = *problem.graph;
  const std::size_t n = g.num_nodes();
  const std::size_t kp = padded_classes(problem.classes);
  // Not filled: the first iteration reads no message and writes every slot of `next`.
  buffers.messages.resize(g.num_slots() * kp);
  buffers.next.resize(g.num_slots() * kp);
  buffers.beliefs.resize(n * kp);
  std::uint8_t* moved_a = buffers.moved.resize(n);
  std::uint8_t* moved_b = buffers.moved_next.resize(n);
  std::uint8_t* same = buffers.same.resize(n);
  std::fill_n(same, n, std::uint8_t{0});
  std::fill_n(moved_a, n, std::uint8_t{1});
  BpRun report;
  for (int iteration = 1; iteration <= settings.max_iterations; ++iteration) {
    if (settings.stop.stop_requested()) break;
    const FastIteration it{problem,
                           buffers.messages.data(),
                           buffers.next.data(),
                           buffers.beliefs.data(),
                           moved_a,
                           moved_b,
                           same,
                           iteration == 1,
                           iteration == 1 ? 0.0f : settings.damping,
                           settings.tolerance,
                           settings.max_product,
                           settings.stop};
    const float change = fast_update_dispatch(it, settings.threads);
    std::swap(buffers.messages, buffers.next);
    std::swap(moved_a, moved_b);
    // The first sweep reads no message and reports no change (0), so it cannot converge.
    if (report.record(iteration, change, iteration > 1 ? settings.tolerance : 0.0f)) break;
  }
  if (report.iterations == 0) {
    // No iteration: the messages are the uniform start.
    std::fill_n(buffers.messages.data(), g.num_slots() * kp, 1.0f);
  }
  return report;
}

void fast_bp_outputs(const FastBpProblem& problem, const FastBpBuffers& buffers,
                     const std::vector<std::uint32_t>& class_ids, std::uint32_t unknown_label,
                     int threads, std::uint32_t* labels, float* marginals) {
  const Graph& g = *problem.graph;
  const int k_count = problem.classes;
  const int kp = padded_classes(k_count);
  const long long n = static_cast<long long>(g.num_nodes());
  const float* messages = buffers.messages.data();
  primlabel::detail::ExceptionBarrier barrier;
#pragma omp parallel num_threads(threads)
  {
    FlushSubnormals flush;
    std::vector<double> b(kp);
#pragma omp for schedule(dynamic, 1024)
    for (long long i = 0; i < n; ++i)
      barrier.run([&] {
        if (!g.active[i]) {
          labels[i] = unknown_label;
          if (marginals)
            for (int k = 0; k < k_count; ++k)
              marginals[std::size_t(k) * n + i] = std::numeric_limits<float>::quiet_NaN();
          return;
        }
        for (int k = 0; k < kp; ++k) b[k] = problem.phi[std::size_t(i) * kp + k];
        int since_rescale = 0;
        for (std::uint32_t q = g.offsets[i]; q < g.offsets[i + 1]; ++q) {
          const float* in = messages + std::size_t(g.reverse[q]) * kp;
          for (int k = 0; k < kp; ++k) b[k] *= in[k];
          if (++since_rescale == kRescaleEvery) {
            scale_to_max_one(b.data(), kp);
            since_rescale = 0;
          }
        }
        int best = 0;  // first maximum: ties go to the lower class index
        for (int k = 1; k < k_count; ++k)
          if (b[k] > b[best]) best = k;
        labels[i] = class_ids[best];
        if (marginals) {
          double sum = 0.0;
          for (int k = 0; k < k_count; ++k) sum += b[k];
          const bool ok = sum > 0.0 && std::isfinite(sum);
          for (int k = 0; k < k_count; ++k)
            marginals[std::size_t(k) * n + i] = static_cast<float>(ok ? b[k] / sum : 1.0 / k_count);
        }
      });
  }
  barrier.rethrow();
}

}  // namespace primlabel::crf::detail
