// Fast Point Feature Histograms (Rusu et al. 2009), computed as PCL 1.13's FPFHEstimation does:
//   1. SPFH(p): for each neighbour q != p, the pair features (alpha, phi, theta) are binned into
//      three 11-bin histograms, each pair adding 100 / (k - 1).
//   2. FPFH(p) = sum over neighbours q at squared distance d > 0 of SPFH(q) / d, each 11-bin
//      sub-histogram then scaled to sum to 100. The paper's variant adds SPFH(p) afterwards.
// Unlike PCL, each point is searched once: pass 1 keeps its neighbour list for pass 2 while the
// lists fit in a memory budget (points beyond it are searched again, with identical results).
// SPFHs are stored row-major, one contiguous 33-float row per point, so pass 2 reads each
// neighbour's signature in one cache-friendly, vectorisable sweep.

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include "feature_neighborhood.hpp"
#include "pair_bins_batch.hpp"
#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel {

namespace {

constexpr int kBins = kFpfhBinsPerFeature;
constexpr std::size_t kBlock = 256;  // points per work item and per neighbour-cache block

// Neighbour lists of pass 1, per block of kBlock points, kept while under the byte budget.
class NeighborCache {
 public:
  NeighborCache(std::size_t points, std::size_t budget_bytes)
      : blocks_((points + kBlock - 1) / kBlock), budget_(budget_bytes) {}

  // Stores the list of `point`; called by the one thread that owns the point's block.
  void store(std::size_t point, std::span<const std::uint32_t> list) {
    Block& block = blocks_[point / kBlock];
    if (block.begin.empty()) block.begin.assign(kBlock + 1, kNotCached);
    const std::size_t bytes = list.size() * sizeof(std::uint32_t);
    if (used_.fetch_add(bytes, std::memory_order_relaxed) + bytes > budget_) {
      used_.fetch_sub(bytes, std::memory_order_relaxed);
      return;
    }
    const std::size_t slot = point % kBlock;
    block.begin[slot] = static_cast<std::uint32_t>(block.indices.size());
    block.indices.insert(block.indices.end(), list.begin(), list.end());
    block.end[slot] = static_cast<std::uint32_t>(block.indices.size());
  }

  // The cached list of `point` (valid while the cache is), or false when it has to be
  // searched again.
  bool load(std::size_t point, std::span<const std::uint32_t>& out) const {
    const Block& block = blocks_[point / kBlock];
    const std::size_t slot = point % kBlock;
    if (block.begin.empty() || block.begin[slot] == kNotCached) return false;
    out = std::span<const std::uint32_t>(block.indices.data() + block.begin[slot],
                                         block.end[slot] - block.begin[slot]);
    return true;
  }

 private:
  static constexpr std::uint32_t kNotCached = std::numeric_limits<std::uint32_t>::max();
  struct Block {
    std::vector<std::uint32_t> begin;
    std::uint32_t end[kBlock];
    std::vector<std::uint32_t> indices;
  };
  std::vector<Block> blocks_;
  std::size_t budget_;
  std::atomic<std::size_t> used_{0};
};

// The value of a bin that `c` pairs fell in, for each c <= neighbours: 100 / (neighbours - 1)
// added c times, as PCL adds it (c * increment rounds differently). Computed once per neighbour
// count and thread: a long chain of dependent additions per bin otherwise.
class IncrementSums {
 public:
  const float* for_neighbors(std::size_t neighbors) {
    // Kept per count up to kKept (at most ~8 MB a thread); larger lists rebuild theirs, which
    // costs less than their pairs.
    constexpr std::size_t kKept = 2048;
    if (neighbors > kKept) {
      fill(neighbors, uncached_);
      return uncached_.data();
    }
    if (neighbors >= tables_.size()) tables_.resize(neighbors + 1);
    std::vector<float>& table = tables_[neighbors];
    if (table.empty()) fill(neighbors, table);
    return table.data();
  }

 private:
  static void fill(std::size_t neighbors, std::vector<float>& table) {
    const float increment = 100.0f / static_cast<float>(neighbors - 1);
    table.resize(neighbors + 1);  // a point missing from its own list pairs with all
    float sum = 0.0f;
    for (std::size_t c = 0; c <= neighbors; ++c, sum += increment) table[c] = sum;
  }
  std::vector<std::vector<float>> tables_;  // by neighbour count; filled when first needed
  std::vector<float> uncached_;
};

// Whether a neighbour takes part: every point when `usable` is null (all have normals).
inline bool takes_part(const char* usable, std::uint32_t q) { return !usable || usable[q]; }

// Scratch space of one thread for the SPFH pass.
struct SpfhScratch {
  NeighborList list;
  detail::PairTargets targets;
  std::vector<std::uint32_t> target_index;  // cloud index of each target
  std::vector<std::uint8_t> alpha, phi, theta, one_sided;
  IncrementSums sums;

  // Room for up to `pairs` targets and their batch.
  void reserve(std::size_t pairs) {
    const std::size_t room = batch_size(pairs);
    targets.resize(room), target_index.resize(room);
    alpha.resize(room), phi.resize(room), theta.resize(room), one_sided.resize(room);
  }
  // The batch for `pairs` (> 0) targets: rounded up to the widest lane count so that no pair
  // falls to the slower scalar tail; the padding repeats the last target, its bins are ignored.
  std::size_t pad(std::size_t pairs) {
    const std::size_t batch = batch_size(pairs);
    for (std::size_t j = pairs; j < batch; ++j)
      targets.set(j, Vec3f(targets.x[pairs - 1], targets.y[pairs - 1], targets.z[pairs - 1]),
                  Vec3f(targets.nx[pairs - 1], targets.ny[pairs - 1], targets.nz[pairs - 1]));
    return batch;
  }
  static std::size_t batch_size(std::size_t pairs) { return (pairs + 7) / 8 * 8; }
};

// Row `spfh` of point p from its neighbour list, every pair computed here (`neighbors` = how
// many of the list take part, p included).
void compute_spfh(const PointCloud& cloud, std::size_t p, std::span<const std::uint32_t> list,
                  const char* usable, std::size_t neighbors, SpfhScratch& scratch, float* spfh) {
  scratch.reserve(list.size());
  std::size_t pairs = 0;
  for (std::uint32_t q : list)
    if (q != p && takes_part(usable, q))
      scratch.targets.set(pairs++, cloud.xyz[q], cloud.normals[q]);
  // A degenerate pair (coincident points) still counts, with zero features: PCL does the same.
  if (pairs > 0)
    detail::pair_bins_batch(cloud.xyz[p], cloud.normals[p], scratch.targets, scratch.pad(pairs),
                            kBins, scratch.alpha.data(), scratch.phi.data(), scratch.theta.data());
  std::uint32_t counts[kFpfhSize] = {};
  for (std::size_t j = 0; j < pairs; ++j) {
    ++counts[scratch.alpha[j]];
    ++counts[kBins + scratch.phi[j]];
    ++counts[2 * kBins + scratch.theta[j]];
  }
  // Repeated float additions, not count * increment: the rounding then matches PCL's bit for bit.
  const float* sum_of = scratch.sums.for_neighbors(neighbors);
  for (int b = 0; b < kFpfhSize; ++b) spfh[b] = sum_of[counts[b]];
}

// A point's tag for the check that every pair a point expects was counted for it once: a sum
// of these tells one set of points from another (an odd multiplier spreads the indices' bits).
inline std::uint64_t tag(std::uint64_t index) { return (index + 1) * 0x9e3779b97f4a7c15ull; }

// One thread's bin counts for every point, in the symmetric SPFH pass: a pair's bins are the
// same from either end (pair_bins_batch), so each pair is computed once, by its lower-index
// point, and counted for both. Integer counts add up the same whatever thread counted them.
struct PairCounts {
  std::vector<std::uint16_t> counts;    // n x kFpfhSize
  std::vector<std::uint64_t> received;  // per point: the tags of the lower points that counted
                                        // a pair for it
  void init(std::size_t n) {
    counts.assign(n * kFpfhSize, 0);
    received.assign(n, 0);
  }
};
constexpr std::size_t kPairCountBytes = kFpfhSize * sizeof(std::uint16_t) + sizeof(std::uint64_t);
// Per-thread counts above this many bytes in all: the per-point pass instead (no result changes).
constexpr std::size_t kPairCountBudget = std::size_t(512) << 20;
// A bin of a point with more neighbours than this could overflow the 16-bit counts: such a
// point's row is computed by the per-point path.
constexpr std::size_t kMaxCountedNeighbors = 65535;

// Counts the pairs of p with its higher-index neighbours, for p and for them, into `mine`;
// returns the sum of the tags of p's lower-index neighbours (what p should receive).
std::uint64_t count_upper_pairs(const PointCloud& cloud, std::size_t p,
                                std::span<const std::uint32_t> list, const char* usable,
                                SpfhScratch& scratch, PairCounts& mine) {
  scratch.reserve(list.size());
  std::size_t pairs = 0;
  std::uint64_t expected = 0;
  for (std::uint32_t q : list) {
    if (!takes_part(usable, q)) continue;
    if (q < p) {
      expected += tag(q);
    } else if (q > p) {
      scratch.targets.set(pairs, cloud.xyz[q], cloud.normals[q]);
      scratch.target_index[pairs++] = q;
    }
  }
  if (pairs == 0) return expected;
  detail::pair_bins_batch(cloud.xyz[p], cloud.normals[p], scratch.targets, scratch.pad(pairs),
                          kBins, scratch.alpha.data(), scratch.phi.data(), scratch.theta.data(),
                          scratch.one_sided.data());
  std::uint16_t* counts = mine.counts.data();
  std::uint16_t* own = counts + p * kFpfhSize;
  const std::uint64_t p_tag = tag(p);
  for (std::size_t j = 0; j < pairs; ++j) {
    const std::uint8_t a = scratch.alpha[j], f = scratch.phi[j], t = scratch.theta[j];
    ++own[a], ++own[kBins + f], ++own[2 * kBins + t];
    const std::uint32_t q = scratch.target_index[j];
    std::uint16_t* other = counts + std::size_t(q) * kFpfhSize;
    mine.received[q] += p_tag;
    if (!scratch.one_sided[j]) {
      ++other[a], ++other[kBins + f], ++other[2 * kBins + t];
      continue;
    }
    std::uint8_t reversed[3];  // a tie or a degenerate pair: q's own view of it
    detail::pair_bins_exact(cloud.xyz[q], cloud.normals[q], cloud.xyz[p], cloud.normals[p], kBins,
                            reversed);
    ++other[reversed[0]], ++other[kBins + reversed[1]], ++other[2 * kBins + reversed[2]];
  }
  return expected;
}

// A subset's band: a needed point whose lower neighbours were not all needed misses their pairs
// in the counts. Those pairs of p, and only those, computed from p's end as compute_spfh computes
// every pair of p, are added to `counts`; returns the sum of their tags (what p then received
// in all). The same bins compute_spfh would count for them, so the row is the same bits.
std::uint64_t count_skipped_lower_pairs(const PointCloud& cloud, std::size_t p,
                                        std::span<const std::uint32_t> list, const char* usable,
                                        const std::vector<std::uint8_t>& needed,
                                        SpfhScratch& scratch, std::uint32_t* counts) {
  scratch.reserve(list.size());
  std::size_t pairs = 0;
  std::uint64_t tags = 0;
  for (std::uint32_t q : list)
    if (q < p && takes_part(usable, q) && !needed[q]) {
      scratch.targets.set(pairs++, cloud.xyz[q], cloud.normals[q]);
      tags += tag(q);
    }
  if (pairs == 0) return tags;
  detail::pair_bins_batch(cloud.xyz[p], cloud.normals[p], scratch.targets, scratch.pad(pairs),
                          kBins, scratch.alpha.data(), scratch.phi.data(), scratch.theta.data());
  for (std::size_t j = 0; j < pairs; ++j) {
    ++counts[scratch.alpha[j]];
    ++counts[kBins + scratch.phi[j]];
    ++counts[2 * kBins + scratch.theta[j]];
  }
  return tags;
}

// Squared distance, recomputed the same way for cached and searched lists so that the weights
// never depend on which of the two a point got.
inline float squared_distance(const Vec3f& a, const Vec3f& b) {
  const float dx = a.x() - b.x(), dy = a.y() - b.y(), dz = a.z() - b.z();
  return (dx * dx + dy * dy) + dz * dz;
}

// Cloned for AVX2 (chosen at load time, so the binary still runs on any x86-64): the 33-bin
// accumulation is a third of the pass. No FMA in either clone, and every bin is its own sum in
// the same order, so both give the same bits.
template <bool kFiltered>
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void weight_spfh_of(const PointCloud& cloud, std::size_t p, const std::vector<float>& spfh,
                    const std::vector<double>& spfh_sums, std::span<const std::uint32_t> list,
                    const char* usable, float* fpfh) {
  alignas(16) float accumulated[kFpfhSize] = {};
  double sum[3] = {0.0, 0.0, 0.0};
  for (std::uint32_t q : list) {
    const float sq_dist = squared_distance(cloud.xyz[p], cloud.xyz[q]);
    // The point itself (and exact duplicates), and points without a normal.
    if (sq_dist == 0.0f || (kFiltered && !usable[q])) continue;
    const float weight = 1.0f / sq_dist;
    const float* row = spfh.data() + std::size_t(q) * kFpfhSize;
    for (int b = 0; b < kFpfhSize; ++b) accumulated[b] += row[b] * weight;
    for (int s = 0; s < 3; ++s) sum[s] += spfh_sums[3 * std::size_t(q) + s] * weight;
  }
  for (int s = 0; s < 3; ++s) {
    const double scale = sum[s] != 0.0 ? 100.0 / sum[s] : 0.0;  // sub-histogram sums to 100
    for (int b = s * kBins; b < (s + 1) * kBins; ++b)
      fpfh[b] = static_cast<float>(accumulated[b] * scale);
  }
}

void weight_spfh(const PointCloud& cloud, std::size_t p, const std::vector<float>& spfh,
                 const std::vector<double>& spfh_sums, std::span<const std::uint32_t> list,
                 const char* usable, float* fpfh) {
  // Two loops, so that a cloud whose points all have normals pays no test per neighbour.
  if (usable)
    weight_spfh_of<true>(cloud, p, spfh, spfh_sums, list, usable, fpfh);
  else
    weight_spfh_of<false>(cloud, p, spfh, spfh_sums, list, usable, fpfh);
}

// The points pass 1 must describe for the wanted ones: each usable wanted point and every
// neighbour of one (pass 2 weighs their histograms).
template <typename NeighborsOf>
std::vector<std::uint8_t> needed_for(std::span<const std::uint8_t> wanted,
                                     const NeighborsOf& neighbors_of,
                                     const std::vector<char>& usable, std::ptrdiff_t blocks,
                                     const RunContext& context) {
  const std::size_t n = wanted.size();
  std::vector<std::uint8_t> needed(n, 0);
  detail::for_each_block(
      blocks, context, [] { return NeighborList(); },
      [&](NeighborList& scratch, std::ptrdiff_t block) {
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        for (std::size_t p = first; p < last; ++p) {
          if (!wanted[p] || !usable[p]) continue;
          std::atomic_ref<std::uint8_t>(needed[p]).store(1, std::memory_order_relaxed);
          for (std::uint32_t q : neighbors_of(p, scratch))
            std::atomic_ref<std::uint8_t>(needed[q]).store(1, std::memory_order_relaxed);
        }
      });
  return needed;
}

// One compute_fpfh call: where each point's neighbours come from, and the SPFH rows of pass 1
// that pass 2 weighs. Pass 1 takes one of two paths (spfh_from_pair_counts, spfh_per_point);
// both give the same bits.
class FpfhRun {
 public:
  FpfhRun(const PointCloud& cloud, const FeatureOptions& options, const RunContext& context,
          const FeatureExtras& extras)
      : cloud_(cloud),
        options_(options),
        context_(context),
        stop_(context.stop),
        usable_(checked_usable_points(cloud, options)),
        index_(detail::ensure_search(cloud, extras.search, owned_search_, stop_)),
        lists_(extras.lists),
        n_(cloud.size()),
        blocks_(static_cast<std::ptrdiff_t>((n_ + kBlock - 1) / kBlock)),
        threads_(detail::resolve_threads(context.threads)),
        use_lists_(lists_ && options.neighborhood.radius > 0.0f &&
                   options.neighborhood.radius <= lists_->neighborhood().radius),
        all_usable_(std::all_of(usable_.begin(), usable_.end(), [](char u) { return u != 0; })),
        usable_or_all_(all_usable_ ? nullptr : usable_.data()),
        cache_(n_, use_lists_ ? 0 : options.neighbor_cache_bytes),
        progress_(context.progress, 2 * n_),
        subset_(!options.wanted.empty()) {
    detail::assign_checked(spfh_, n_ * kFpfhSize, 0.0f, stop_, "FPFH");
    detail::assign_checked(spfh_sums_, n_ * 3, 0.0, stop_, "FPFH");
    detail::assign_checked(neighbor_count_, n_, std::uint32_t(0), stop_, "FPFH");
    if (subset_ && options.wanted.size() != n_)
      throw std::invalid_argument("FPFH: " + std::to_string(options.wanted.size()) +
                                  " wanted flags for " + std::to_string(n_) + " points");
    // Only some points wanted: pass 1 on them and their neighbours alone. A needed point that
    // then misses a pair its list expects (its lower neighbour was not needed) takes the
    // per-point path like any other, so the rows are the same bits.
    if (subset_)
      needed_ = needed_for(
          options.wanted,
          [this](std::size_t p, NeighborList& scratch) { return neighbors_of(p, scratch); },
          usable_, blocks_, context.with_threads(threads_));
    throw_if_stopped(stop_, "FPFH");
  }

  // Radius neighbourhoods are symmetric (q is within r of p exactly when p is within r of q: the
  // same float distance), so pass 1 may compute each pair once, while the counts fit in memory.
  bool pairs_symmetric() const {
    const Neighborhood& hood = options_.neighborhood;
    return hood.radius > 0.0f && hood.k == 0 &&
           n_ * kPairCountBytes * std::size_t(threads_) <= kPairCountBudget;
  }

  // Pass 1, each pair once. A list cut by the cap is not the whole ball: its point's row, and the
  // rows of points that then miss a pair, take the per-point path.
  void spfh_from_pair_counts() {
    std::vector<PairCounts> per_thread(static_cast<std::size_t>(threads_));
    std::vector<std::uint64_t> expected(n_, 0);
    std::vector<std::uint8_t> cut(n_, 0);
    std::atomic<std::size_t> next_thread{0};
    struct CountScratch {
      SpfhScratch pairs;
      PairCounts* counts;
    };
    const Neighborhood& hood = options_.neighborhood;
    detail::for_each_block(
        blocks_, context_.with_threads(threads_),
        [&] {
          PairCounts* mine = &per_thread[next_thread++];
          mine->init(n_);
          return CountScratch{SpfhScratch(), mine};
        },
        [&](CountScratch& scratch, std::ptrdiff_t block) {
          const auto [first, last] = block_range(block);
          for (std::size_t p = first; p < last; ++p) {
            if (stop_.stop_requested()) return;
            if (!takes_part_in_pass_1(p)) continue;
            const std::span<const std::uint32_t> list = neighbors_of(p, scratch.pairs.list);
            keep_for_pass_2(p, list);
            cut[p] = hood.max_neighbors > 0 && list.size() >= std::size_t(hood.max_neighbors);
            expected[p] =
                count_upper_pairs(cloud_, p, list, usable_or_all_, scratch.pairs, *scratch.counts);
          }
          progress_.add((last - first) / 2);
        });
    throw_if_stopped(stop_, "FPFH");
    const std::size_t used = next_thread.load();
    // Rows from the summed counts. A point whose list was cut, that did not receive exactly the
    // pairs its own list expects (a lower neighbour's cut list, or a search that is not
    // symmetric after all), or whose counts could overflow, gets its row by the per-point path:
    // the result is the same either way.
    detail::for_each_block(
        blocks_, context_.with_threads(threads_), [] { return SpfhScratch(); },
        [&](SpfhScratch& scratch, std::ptrdiff_t block) {
          const auto [first, last] = block_range(block);
          for (std::size_t p = first; p < last; ++p) {
            if (stop_.stop_requested()) return;
            if (!takes_part_in_pass_1(p) || neighbor_count_[p] < 2) continue;
            std::uint64_t received = 0;
            std::uint32_t counts[kFpfhSize] = {};
            for (std::size_t t = 0; t < used; ++t) {
              received += per_thread[t].received[p];
              const std::uint16_t* row = per_thread[t].counts.data() + p * kFpfhSize;
              for (int b = 0; b < kFpfhSize; ++b) counts[b] += row[b];
            }
            float* row = &spfh_[p * kFpfhSize];
            bool counted = !cut[p] && neighbor_count_[p] <= kMaxCountedNeighbors;
            std::span<const std::uint32_t> list;
            if (counted && received != expected[p] && subset_) {
              // On the subset's band: only the pairs with the lower neighbours pass 1 skipped.
              if (!cache_.load(p, list)) list = neighbors_of(p, scratch.list);
              received += count_skipped_lower_pairs(cloud_, p, list, usable_or_all_, needed_,
                                                    scratch, counts);
            }
            if (!counted || received != expected[p]) {
              if (list.empty() && !cache_.load(p, list)) list = neighbors_of(p, scratch.list);
              compute_spfh(cloud_, p, list, usable_or_all_, neighbor_count_[p], scratch, row);
            } else {
              const float* sum_of = scratch.sums.for_neighbors(neighbor_count_[p]);
              for (int b = 0; b < kFpfhSize; ++b) row[b] = sum_of[counts[b]];
            }
            finish_row(p);
          }
          progress_.add(last - first - (last - first) / 2);
        });
    throw_if_stopped(stop_, "FPFH");
  }

  // Pass 1, every pair of every point: k-nearest neighbourhoods and counts beyond the memory bound.
  void spfh_per_point() {
    detail::for_each_block(
        blocks_, context_.with_threads(threads_), [] { return SpfhScratch(); },
        [&](SpfhScratch& scratch, std::ptrdiff_t block) {
          const auto [first, last] = block_range(block);
          for (std::size_t p = first; p < last; ++p) {
            // Per point: a stop is honoured within one (capped) neighbourhood's time.
            if (stop_.stop_requested()) return;
            if (!takes_part_in_pass_1(p)) continue;
            const std::span<const std::uint32_t> list = neighbors_of(p, scratch.list);
            keep_for_pass_2(p, list);
            if (neighbor_count_[p] < 2) continue;
            compute_spfh(cloud_, p, list, usable_or_all_, neighbor_count_[p], scratch,
                         &spfh_[p * kFpfhSize]);
            finish_row(p);
          }
          progress_.add(last - first);
        });
    throw_if_stopped(stop_, "FPFH");
  }

  // Pass 2: each wanted point's neighbours' SPFH rows, weighed by inverse squared distance.
  Descriptors weigh_neighbors(FeatureStats* stats) {
    std::vector<float> fpfh;
    detail::assign_checked(fpfh, n_ * kFpfhSize, 0.0f, stop_, "FPFH");
    std::atomic<std::size_t> computed{0}, isolated{0};
    detail::for_each_block(
        blocks_, context_.with_threads(threads_), [] { return NeighborList(); },
        [&](NeighborList& scratch, std::ptrdiff_t block) {
          std::size_t block_computed = 0, block_isolated = 0;
          const auto [first, last] = block_range(block);
          for (std::size_t p = first; p < last; ++p) {
            if (stop_.stop_requested()) return;
            float* out = &fpfh[p * kFpfhSize];
            if (!usable_[p] || (subset_ && !options_.wanted[p])) {
              std::fill(out, out + kFpfhSize, std::numeric_limits<float>::quiet_NaN());
              continue;
            }
            if (neighbor_count_[p] < 2) {
              ++block_isolated;  // stays all zero, as in PCL
              continue;
            }
            std::span<const std::uint32_t> list;
            if (!cache_.load(p, list)) list = neighbors_of(p, scratch);
            weight_spfh(cloud_, p, spfh_, spfh_sums_, list, usable_or_all_, out);
            if (options_.fpfh_variant == FpfhVariant::kWithOwnSpfh)
              for (int b = 0; b < kFpfhSize; ++b) out[b] += spfh_[p * kFpfhSize + b];
            ++block_computed;
          }
          computed += block_computed, isolated += block_isolated;
          progress_.add(last - first);
        });
    throw_if_stopped(stop_, "FPFH");
    progress_.finish();
    if (stats) *stats = FeatureStats{computed.load(), isolated.load(), n_ - computed - isolated};
    return Descriptors(kFpfhSize, std::move(fpfh));
  }

 private:
  static std::vector<char> checked_usable_points(const PointCloud& cloud,
                                                 const FeatureOptions& options) {
    if (!options.neighborhood.valid())
      throw std::invalid_argument("FPFH: invalid neighbourhood " + options.neighborhood.describe());
    return detail::usable_points(cloud, "FPFH");
  }

  std::pair<std::size_t, std::size_t> block_range(std::ptrdiff_t block) const {
    const std::size_t first = std::size_t(block) * kBlock;
    return {first, std::min(n_, first + kBlock)};
  }

  bool takes_part_in_pass_1(std::size_t p) const { return usable_[p] && (!subset_ || needed_[p]); }

  // Point p's neighbours (with or without a normal), from the shared lists (no copy where they
  // answer as they are) or a search into `scratch`. Radius neighbourhoods need no order: every
  // sum is order-independent up to rounding, and tree order is itself deterministic.
  std::span<const std::uint32_t> neighbors_of(std::size_t p, NeighborList& scratch) const {
    if (use_lists_) return lists_->view(p, options_.neighborhood, scratch);
    index_.find(cloud_.xyz[p], options_.neighborhood, scratch, /*sorted=*/false);
    return std::span<const std::uint32_t>(scratch.indices);
  }

  // What pass 2 needs of p's list: the list itself (when searched; shared lists are read again
  // at no cost) and how many take part.
  void keep_for_pass_2(std::size_t p, std::span<const std::uint32_t> list) {
    cache_.store(p, list);
    const std::size_t taking_part =
        all_usable_ ? list.size()
                    : std::size_t(std::count_if(list.begin(), list.end(),
                                                [&](std::uint32_t q) { return usable_[q] != 0; }));
    neighbor_count_[p] = static_cast<std::uint32_t>(
        std::min<std::size_t>(taking_part, std::numeric_limits<std::uint32_t>::max()));
  }

  void finish_row(std::size_t p) {
    const float* row = &spfh_[p * kFpfhSize];
    for (int b = 0; b < kFpfhSize; ++b) spfh_sums_[3 * p + b / kBins] += row[b];
  }

  const PointCloud& cloud_;
  const FeatureOptions& options_;
  const RunContext& context_;
  const std::stop_token& stop_;
  const std::vector<char> usable_;
  std::unique_ptr<NeighborSearch> owned_search_;
  const NeighborSearch& index_;
  const NeighborLists* lists_;
  const std::size_t n_;
  const std::ptrdiff_t blocks_;
  const int threads_;
  const bool use_lists_;
  const bool all_usable_;
  const char* usable_or_all_;  // points without a normal skipped; null when every point has one
  NeighborCache cache_;
  detail::ProgressCounter progress_;
  const bool subset_;
  std::vector<std::uint8_t> needed_;  // subset: the points pass 1 describes
  std::vector<float> spfh_;
  std::vector<double> spfh_sums_;              // per sub-histogram, for the normalisation
  std::vector<std::uint32_t> neighbor_count_;  // per point: its list's points that take part
};

}  // namespace

Descriptors compute_fpfh(const PointCloud& cloud, const FeatureOptions& options,
                         const RunContext& context, const FeatureExtras& extras) {
  FpfhRun run(cloud, options, context, extras);
  if (run.pairs_symmetric())
    run.spfh_from_pair_counts();
  else
    run.spfh_per_point();
  return run.weigh_neighbors(extras.stats);
}

}  // namespace primlabel
