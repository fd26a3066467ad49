#include "inference/mean_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "primlabel/geometry/parallel.hpp"

namespace primlabel::crf::detail {

using primlabel::detail::parallel_for;
using primlabel::detail::Schedule;

namespace {

// Pads get this score, so exp makes them exactly 0 (and -inf would risk inf - inf).
constexpr float kPadScore = -1e30f;

template <int KP>
class MeanFieldUpdater {
  using ArrayF = Eigen::Array<float, KP, 1>;
  using ConstMapF = Eigen::Map<const ArrayF>;

 public:
  MeanFieldUpdater(int k_count, int kp) : k_(k_count), kp_(kp), a_(kp), fresh_(kp), pad_(kp) {
    for (int k = 0; k < kp; ++k) pad_(k) = k < k_count ? 0.0f : kPadScore;
  }

  // fresh = softmax(a) over the K real classes, pads 0 (a's pads are 0 on entry).
  void softmax() {
    a_ += pad_;  // in registers: scalar stores into a_ would stall the vector loads that follow
    fresh_ = (a_ - a_.maxCoeff()).exp();
    fresh_ *= 1.0f / fresh_.sum();
  }

  void start(const MeanFieldProblem& pr, std::size_t i, float* q) {
    a_ = ConstMapF(pr.node_scores + i * kp_, kp_);
    softmax();
    Eigen::Map<ArrayF>(q + i * kp_, kp_) = fresh_;
  }

  float update(const MeanFieldProblem& pr, const float* q, float* next, float keep, std::size_t i) {
    const Graph& g = *pr.graph;
    a_ = ConstMapF(pr.node_scores + i * kp_, kp_);
    for (std::uint32_t p = g.offsets[i]; p < g.offsets[i + 1]; ++p)
      a_ += ConstMapF(q + std::size_t(g.neighbors[p]) * kp_, kp_) *
            ConstMapF(pr.edge_scores + std::size_t(pr.edge_of[p]) * kp_, kp_);
    softmax();
    const ConstMapF old(q + i * kp_, kp_);
    Eigen::Map<ArrayF> out(next + i * kp_, kp_);
    out = (1.0f - keep) * fresh_ + keep * old;
    return (out - old).abs().maxCoeff();
  }

 private:
  int k_, kp_;
  ArrayF a_, fresh_, pad_;
};

// What each thread keeps through a parallel pass: its subnormal mode, its updater, whether it saw
// the stop (then it skips its remaining nodes) and the largest change it made.
template <int KP>
struct MeanFieldThread {
  FlushSubnormals flush;  // exp of very negative scores would run into slow subnormals
  MeanFieldUpdater<KP> updater;
  bool stopped = false;
  float max_change = 0.0f;
};

template <int KP>
BpRun run(const MeanFieldProblem& pr, const BpSettings& settings, const RunContext& context,
          MeanFieldBuffers& buffers) {
  const int threads = primlabel::detail::resolve_threads(context.threads);
  ScratchBuffer<float>& q_buf = buffers.q;
  ScratchBuffer<float>& next_buf = buffers.next;
  const Graph& g = *pr.graph;
  const long long n = static_cast<long long>(g.num_nodes());
  const int kp = padded_classes(pr.classes);
  float* q = q_buf.resize(g.num_nodes() * kp);
  float* next = next_buf.resize(g.num_nodes() * kp);
  // Start from the node-only posterior, in both buffers: rows without neighbours are never
  // rewritten.
  const auto make_thread = [&] {
    return MeanFieldThread<KP>{FlushSubnormals{}, MeanFieldUpdater<KP>(pr.classes, kp)};
  };
  parallel_for(n, threads, Schedule::Static(), make_thread,
               [&](MeanFieldThread<KP>& thread, std::ptrdiff_t i) {
                 if (g.active[i]) {
                   thread.updater.start(pr, i, q);
                 } else {
                   std::fill_n(q + i * kp, kp, 0.0f);
                 }
                 std::copy_n(q + i * kp, kp, next + i * kp);
               });
  std::uint8_t* moved_before = buffers.moved.resize(g.num_nodes());
  std::uint8_t* moved = buffers.moved_next.resize(g.num_nodes());
  std::uint8_t* same = buffers.same.resize(g.num_nodes());
  std::fill_n(moved_before, g.num_nodes(), std::uint8_t{1});
  std::fill_n(same, g.num_nodes(), std::uint8_t{1});  // both buffers start equal
  BpRun report;
  for (int iteration = 1; iteration <= settings.max_iterations; ++iteration) {
    if (context.stopped()) break;
    // The largest change of any node: a maximum, so the same whatever the threads.
    float max_change = 0.0f;
    parallel_for(
        n, threads, Schedule::Dynamic(1024), make_thread,
        [&](MeanFieldThread<KP>& thread, std::ptrdiff_t i) {
          if ((i & 1023) == 0) thread.stopped = thread.stopped || context.stopped();
          if (thread.stopped) return;
          if (g.offsets[i] == g.offsets[i + 1]) return;  // no neighbours: q is final
          // Skip a node whose q and neighbours' q all settled last iteration (decided from the
          // previous iteration alone: thread-count independent).
          bool needed = moved_before[i] != 0;
          for (std::uint32_t p = g.offsets[i]; !needed && p < g.offsets[i + 1]; ++p)
            needed = moved_before[g.neighbors[p]] != 0;
          if (!needed) {
            if (!same[i]) {
              std::copy_n(q + i * kp, kp, next + i * kp);
              same[i] = 1;
            }
            moved[i] = 0;
            return;
          }
          same[i] = 0;
          const float change = thread.updater.update(pr, q, next, settings.damping, i);
          moved[i] = change >= settings.tolerance;
          thread.max_change = std::max(thread.max_change, change);
        },
        [&](const MeanFieldThread<KP>& thread) {
          max_change = std::max(max_change, thread.max_change);
        });
    std::swap(q_buf, next_buf);
    std::swap(q, next);
    std::swap(moved_before, moved);
    if (report.record(iteration, max_change, settings.tolerance)) break;
  }
  return report;
}

}  // namespace

BpRun run_mean_field(const MeanFieldProblem& problem, const BpSettings& settings,
                     const RunContext& context, MeanFieldBuffers& buffers) {
  switch (padded_classes(problem.classes)) {
    case 4:
      return run<4>(problem, settings, context, buffers);
    case 8:
      return run<8>(problem, settings, context, buffers);
    case 12:
      return run<12>(problem, settings, context, buffers);
    case 16:
      return run<16>(problem, settings, context, buffers);
    default:
      return run<Eigen::Dynamic>(problem, settings, context, buffers);
  }
}

}  // namespace primlabel::crf::detail
