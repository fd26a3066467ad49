#include "inference/belief_propagation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "primlabel/geometry/parallel.hpp"

namespace primlabel::crf::detail {
namespace {

// Products of more than this many messages are rescaled, so a belief never underflows double.
constexpr int kRescaleEvery = 16;
// Nodes per block of the parallel loops (the stop check and the unit of work).
constexpr std::ptrdiff_t kNodeBlock = 1024;

// The uniform messages before the first iteration of a run from reset() (never stored).
const std::array<float, kMaxBpClasses> kOnes = [] {
  std::array<float, kMaxBpClasses> ones;
  ones.fill(1.0f);
  return ones;
}();

void scale_to_max_one(double* v, int k_count) {
  double mx = 0.0;
  for (int k = 0; k < k_count; ++k) mx = std::max(mx, v[k]);
  if (mx > 0.0) {
    const double inv = 1.0 / mx;
    for (int k = 0; k < k_count; ++k) v[k] *= inv;
  }
}

std::ptrdiff_t node_blocks(std::size_t n) {
  return static_cast<std::ptrdiff_t>((n + kNodeBlock - 1) / kNodeBlock);
}

// b / sum(b) over the K real classes, uniform when the sum degenerates.
template <typename T>
void normalise(const double* b, int k_count, T* out, std::size_t stride) {
  double sum = 0.0;
  for (int k = 0; k < k_count; ++k) sum += b[k];
  const bool ok = sum > 0.0 && std::isfinite(sum);
  for (int k = 0; k < k_count; ++k)
    out[std::size_t(k) * stride] = static_cast<T>(ok ? b[k] / sum : 1.0 / k_count);
}

// One node's update on the padded layout. KP is the padded class count when known at compile
// time (Eigen then keeps whole rows in SSE registers) or Eigen::Dynamic.
template <int KP>
class NodeUpdater {
  using ArrayF = Eigen::Array<float, KP, 1>;
  using ArrayD = Eigen::Array<double, KP, 1>;
  using MapF = Eigen::Map<ArrayF>;
  using ConstMapF = Eigen::Map<const ArrayF>;

 public:
  NodeUpdater(int k_count, int kp)
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
  float update(float& message_change, const Graph& g, const BpPotentials& pr, const float* old,
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
struct Sweep {
  const BpPotentials& pr;
  const float* old;
  float* next;
  float* beliefs;
  const std::uint8_t* moved_before;  // per node: its messages moved >= tolerance last iteration
  std::uint8_t* moved;               // ... this iteration
  std::uint8_t* same;                // per node: its messages are equal in both buffers
  float* block_change;               // per block: the largest belief change
  bool first;                        // from the uniform start: no message is read
  float keep;
  float tolerance;
  bool max_product;
  bool fixed_point;  // update every node; report message (not belief) changes
};

// One iteration over fixed node blocks; returns the largest belief change.
template <int KP>
float sweep(const Sweep& it, const RunContext& context) {
  const Graph& g = *it.pr.graph;
  const std::size_t n = g.num_nodes();
  const int kp = padded_classes(it.pr.classes);
  const std::ptrdiff_t blocks = node_blocks(n);
  std::fill_n(it.block_change, blocks, 0.0f);
  struct Scratch {
    std::unique_ptr<FlushSubnormals> flush;  // for the thread's whole share of the sweep
    NodeUpdater<KP> updater;
  };
  primlabel::detail::for_each_block(
      blocks, context,
      [&] {
        return Scratch{std::make_unique<FlushSubnormals>(), NodeUpdater<KP>(it.pr.classes, kp)};
      },
      [&](Scratch& scratch, std::ptrdiff_t block) {
        float block_max = 0.0f;
        const std::size_t first = std::size_t(block) * kNodeBlock;
        const std::size_t last = std::min(n, first + kNodeBlock);
        for (std::size_t i = first; i < last; ++i) {
          const std::uint32_t begin = g.offsets[i], end = g.offsets[i + 1];
          if (begin == end) continue;
          // A node whose messages and inputs all settled (moved < tolerance last iteration)
          // would only repeat itself: skip it. Decided from the previous iteration alone, so the
          // result still does not depend on the thread count.
          bool needed = it.first || it.fixed_point || it.moved_before[i];
          for (std::uint32_t p = begin; !needed && p < end; ++p)
            needed = it.moved_before[g.neighbors[p]] != 0;
          if (!needed) {
            if (!it.same[i]) {
              std::copy(it.old + std::size_t(begin) * kp, it.old + std::size_t(end) * kp,
                        it.next + std::size_t(begin) * kp);
              it.same[i] = 1;
            }
            it.moved[i] = 0;
            continue;
          }
          it.same[i] = 0;
          float message_change = 0.0f;
          const float change =
              scratch.updater.update(message_change, g, it.pr, it.old, it.next, it.beliefs,
                                     it.first, it.keep, it.max_product, i);
          it.moved[i] = message_change >= it.tolerance;
          block_max = std::max(block_max, it.fixed_point ? message_change : change);
        }
        it.block_change[block] = block_max;
      });
  float max_change = 0.0f;
  for (std::ptrdiff_t b = 0; b < blocks; ++b) max_change = std::max(max_change, it.block_change[b]);
  return max_change;
}

float sweep_dispatch(const Sweep& it, const RunContext& context) {
  switch (padded_classes(it.pr.classes)) {
    case 4:
      return sweep<4>(it, context);
    case 8:
      return sweep<8>(it, context);
    case 12:
      return sweep<12>(it, context);
    case 16:
      return sweep<16>(it, context);
    default:
      return sweep<Eigen::Dynamic>(it, context);
  }
}

}  // namespace

void BeliefPropagation::reset(const BpPotentials& potentials) {
  if (potentials.classes < 1 || potentials.classes > kMaxBpClasses)
    throw std::invalid_argument("loopy BP: the number of classes must be in [1, " +
                                std::to_string(kMaxBpClasses) + "]");
  p_ = potentials;
  const Graph& g = *p_.graph;
  const std::size_t kp = padded_classes(p_.classes);
  // Not filled: the first iteration reads no message and writes every slot of `next`.
  messages_.resize(g.num_slots() * kp);
  next_.resize(g.num_slots() * kp);
  beliefs_.resize(g.num_nodes() * kp);
  moved_.resize(g.num_nodes());
  moved_next_.resize(g.num_nodes());
  same_.resize(g.num_nodes());
  block_change_.resize(node_blocks(g.num_nodes()));
  uniform_ = true;
}

void BeliefPropagation::set_potentials(const BpPotentials& potentials) {
  if (uniform_ || !p_.graph || potentials.graph->num_slots() != p_.graph->num_slots() ||
      potentials.graph->num_nodes() != p_.graph->num_nodes() || potentials.classes != p_.classes)
    return reset(potentials);  // nothing to warm-start from
  p_ = potentials;
}

BpRun BeliefPropagation::run(const BpSettings& settings, const RunContext& context) {
  if (!p_.graph) throw std::logic_error("loopy BP: run before reset");
  const std::size_t n = p_.graph->num_nodes();
  std::uint8_t* moved_a = moved_.data();
  std::uint8_t* moved_b = moved_next_.data();
  std::fill_n(same_.data(), n, std::uint8_t{0});
  std::fill_n(moved_a, n, std::uint8_t{1});  // every node is computed in the first iteration
  const bool from_uniform = uniform_;
  BpRun report;
  for (int iteration = 1; iteration <= settings.max_iterations; ++iteration) {
    if (context.stopped()) break;
    const bool first = from_uniform && iteration == 1;
    const Sweep it{p_,
                   messages_.data(),
                   next_.data(),
                   beliefs_.data(),
                   moved_a,
                   moved_b,
                   same_.data(),
                   block_change_.data(),
                   first,
                   first ? 0.0f : settings.damping,
                   settings.tolerance,
                   settings.max_product,
                   settings.fixed_point};
    const float change = sweep_dispatch(it, context);
    std::swap(messages_, next_);
    std::swap(moved_a, moved_b);
    uniform_ = false;
    const bool can_converge = settings.fixed_point ? !first : iteration > 1;
    if (report.record(iteration, change, can_converge ? settings.tolerance : 0.0f)) break;
  }
  return report;
}

const float* BeliefPropagation::incoming(std::uint32_t slot) const {
  return uniform_ ? kOnes.data()
                  : messages_.data() + std::size_t(slot) * padded_classes(p_.classes);
}

const float* BeliefPropagation::message(std::size_t slot) const {
  return incoming(static_cast<std::uint32_t>(slot));
}

std::span<const float> BeliefPropagation::messages() const {
  if (uniform_ || !p_.graph) return {};
  return {messages_.data(), p_.graph->num_slots() * padded_classes(p_.classes)};
}

void BeliefPropagation::set_messages(std::span<const float> messages) {
  if (!p_.graph || messages.size() != p_.graph->num_slots() * padded_classes(p_.classes))
    throw std::invalid_argument("loopy BP: set_messages with the wrong size");
  std::copy(messages.begin(), messages.end(), messages_.data());
  uniform_ = false;
}

void BeliefPropagation::product(std::size_t i, double* b) const {
  const Graph& g = *p_.graph;
  const int kp = padded_classes(p_.classes);
  for (int k = 0; k < kp; ++k) b[k] = p_.phi[i * kp + k];
  int since_rescale = 0;
  for (std::uint32_t q = g.offsets[i]; q < g.offsets[i + 1]; ++q) {
    const float* in = incoming(g.reverse[q]);
    for (int k = 0; k < kp; ++k) b[k] *= in[k];
    if (++since_rescale == kRescaleEvery) {
      scale_to_max_one(b, kp);
      since_rescale = 0;
    }
  }
}

void BeliefPropagation::beliefs(std::size_t node, std::span<double> out) const {
  const int k_count = p_.classes;
  if (!p_.graph->active[node]) {
    std::fill_n(out.data(), k_count, std::numeric_limits<double>::quiet_NaN());
    return;
  }
  std::array<double, kMaxBpClasses> b;  // padded_classes(K) <= kMaxBpClasses: no allocation
  product(node, b.data());
  normalise(b.data(), k_count, out.data(), 1);
}

void BeliefPropagation::outputs(const std::vector<std::uint32_t>& class_ids,
                                std::uint32_t unknown_label, const RunContext& context,
                                std::uint32_t* labels, float* marginals) const {
  const Graph& g = *p_.graph;
  const int k_count = p_.classes;
  const int kp = padded_classes(k_count);
  const std::size_t n = g.num_nodes();
  struct Scratch {
    std::unique_ptr<FlushSubnormals> flush;
    std::vector<double> b;
  };
  primlabel::detail::for_each_block(
      node_blocks(n), context,
      [&] {
        return Scratch{std::make_unique<FlushSubnormals>(), std::vector<double>(kp)};
      },
      [&](Scratch& scratch, std::ptrdiff_t block) {
        const std::size_t first = std::size_t(block) * kNodeBlock;
        const std::size_t last = std::min(n, first + kNodeBlock);
        double* b = scratch.b.data();
        for (std::size_t i = first; i < last; ++i) {
          if (!g.active[i]) {
            labels[i] = unknown_label;
            if (marginals)
              for (int k = 0; k < k_count; ++k)
                marginals[std::size_t(k) * n + i] = std::numeric_limits<float>::quiet_NaN();
            continue;
          }
          product(i, b);
          int best = 0;  // first maximum: ties go to the lower class index
          for (int k = 1; k < k_count; ++k)
            if (b[k] > b[best]) best = k;
          labels[i] = class_ids[best];
          if (marginals) normalise(b, k_count, marginals + i, n);
        }
      });
}

std::size_t BeliefPropagation::bytes() const {
  return messages_.bytes() + next_.bytes() + beliefs_.bytes() + moved_.bytes() +
         moved_next_.bytes() + same_.bytes() + block_change_.bytes();
}

void BeliefPropagation::release() {
  for (auto* buffer : {&messages_, &next_, &beliefs_, &block_change_}) buffer->release();
  for (auto* buffer : {&moved_, &moved_next_, &same_}) buffer->release();
  p_ = {};
  uniform_ = true;
}

}  // namespace primlabel::crf::detail
