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
  void store(std::size_t point, const NeighborList& list) {
    Block& block = blocks_[point / kBlock];
    if (block.begin.empty()) block.begin.assign(kBlock + 1, kNotCached);
    const std::size_t bytes = list.size() * sizeof(std::uint32_t);
    if (used_.fetch_add(bytes, std::memory_order_relaxed) + bytes > budget_) {
      used_.fetch_sub(bytes, std::memory_order_relaxed);
      return;
    }
    const std::size_t slot = point % kBlock;
    block.begin[slot] = static_cast<std::uint32_t>(block.indices.size());
    block.indices.insert(block.indices.end(), list.indices.begin(), list.indices.end());
    block.end[slot] = static_cast<std::uint32_t>(block.indices.size());
  }

  // The cached list of `point`, or false when it has to be searched again.
  bool load(std::size_t point, NeighborList& out) const {
    const Block& block = blocks_[point / kBlock];
    const std::size_t slot = point % kBlock;
    if (block.begin.empty() || block.begin[slot] == kNotCached) return false;
    out.indices.assign(block.indices.begin() + block.begin[slot],
                       block.indices.begin() + block.end[slot]);
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

// Scratch space of one thread for compute_spfh.
struct SpfhScratch {
  detail::PairTargets targets;
  std::vector<std::uint8_t> alpha, phi, theta;
  IncrementSums sums;
};

void compute_spfh(const PointCloud& cloud, std::size_t p, const NeighborList& neighbors,
                  SpfhScratch& scratch, float* spfh) {
  scratch.targets.resize(neighbors.size());
  std::size_t pairs = 0;
  for (std::uint32_t q : neighbors.indices)
    if (q != p) scratch.targets.set(pairs++, cloud.xyz[q], cloud.normals[q]);
  scratch.alpha.resize(pairs), scratch.phi.resize(pairs), scratch.theta.resize(pairs);
  // A degenerate pair (coincident points) still counts, with zero features: PCL does the same.
  detail::pair_bins_batch(cloud.xyz[p], cloud.normals[p], scratch.targets, pairs, kBins,
                          scratch.alpha.data(), scratch.phi.data(), scratch.theta.data());
  std::uint32_t counts[kFpfhSize] = {};
  for (std::size_t j = 0; j < pairs; ++j) {
    ++counts[scratch.alpha[j]];
    ++counts[kBins + scratch.phi[j]];
    ++counts[2 * kBins + scratch.theta[j]];
  }
  // Repeated float additions, not count * increment: the rounding then matches PCL's bit for bit.
  const float* sum_of = scratch.sums.for_neighbors(neighbors.size());
  for (int b = 0; b < kFpfhSize; ++b) spfh[b] = sum_of[counts[b]];
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
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void weight_spfh(const PointCloud& cloud, std::size_t p, const std::vector<float>& spfh,
                 const std::vector<double>& spfh_sums, const NeighborList& neighbors, float* fpfh) {
  alignas(16) float accumulated[kFpfhSize] = {};
  double sum[3] = {0.0, 0.0, 0.0};
  for (std::uint32_t q : neighbors.indices) {
    const float sq_dist = squared_distance(cloud.xyz[p], cloud.xyz[q]);
    if (sq_dist == 0.0f) continue;  // the point itself (and exact duplicates)
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

}  // namespace

Descriptors compute_fpfh(const PointCloud& cloud, const FeatureOptions& options,
                         const RunContext& context, FeatureStats* stats,
                         const NeighborSearch* search, const NeighborLists* lists) {
  const std::stop_token& stop = context.stop;
  if (!options.neighborhood.valid())
    throw std::invalid_argument("FPFH: invalid neighbourhood " + options.neighborhood.describe());
  const std::vector<char> usable = detail::usable_points(cloud, "FPFH");
  std::unique_ptr<NeighborSearch> owned;
  const NeighborSearch& index = detail::ensure_search(cloud, search, owned, stop);

  const std::size_t n = cloud.size();
  const std::ptrdiff_t blocks = static_cast<std::ptrdiff_t>((n + kBlock - 1) / kBlock);
  const int threads = detail::resolve_threads(context.threads);
  // Radius neighbourhoods need no order: every sum below is order-independent up to rounding,
  // and tree order is itself deterministic.
  const bool sorted = false;
  const bool use_lists = lists && options.neighborhood.radius > 0.0f &&
                         options.neighborhood.radius <= lists->neighborhood().radius;
  // Point p's neighbours that have a normal, from the shared lists or a search.
  const auto neighbors_of = [&](std::size_t p, NeighborList& out) {
    if (!use_lists) {
      detail::usable_neighbors(index, cloud, usable, p, options.neighborhood, sorted, out);
      return;
    }
    lists->find(p, options.neighborhood, out);
    detail::keep_usable(usable, out);
  };

  std::vector<float> spfh;
  std::vector<double> spfh_sums;  // per sub-histogram, for the normalisation
  detail::assign_checked(spfh, n * kFpfhSize, 0.0f, stop, "FPFH");
  detail::assign_checked(spfh_sums, n * 3, 0.0, stop, "FPFH");
  NeighborCache cache(n, options.neighbor_cache_bytes);
  detail::ProgressCounter progress(context.progress, 2 * n);
  struct Pass1Scratch {
    NeighborList neighbors;
    SpfhScratch pairs;
  };
  detail::for_each_block(
      blocks, context.with_threads(threads), [] { return Pass1Scratch(); },
      [&](Pass1Scratch& scratch, std::ptrdiff_t block) {
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        for (std::size_t p = first; p < last; ++p) {
          // Per point: a stop is honoured within one (capped) neighbourhood's time.
          if (stop.stop_requested()) return;
          if (!usable[p]) continue;
          NeighborList& neighbors = scratch.neighbors;
          neighbors_of(p, neighbors);
          cache.store(p, neighbors);
          if (neighbors.size() < 2) continue;
          float* row = &spfh[p * kFpfhSize];
          compute_spfh(cloud, p, neighbors, scratch.pairs, row);
          for (int b = 0; b < kFpfhSize; ++b) spfh_sums[3 * p + b / kBins] += row[b];
        }
        progress.add(last - first);
      });

  throw_if_stopped(stop, "FPFH");

  std::vector<float> fpfh;
  detail::assign_checked(fpfh, n * kFpfhSize, 0.0f, stop, "FPFH");
  std::atomic<std::size_t> computed{0}, isolated{0};
  detail::for_each_block(
      blocks, context.with_threads(threads), [] { return NeighborList(); },
      [&](NeighborList& neighbors, std::ptrdiff_t block) {
        std::size_t block_computed = 0, block_isolated = 0;
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        for (std::size_t p = first; p < last; ++p) {
          if (stop.stop_requested()) return;
          float* out = &fpfh[p * kFpfhSize];
          if (!usable[p]) {
            std::fill(out, out + kFpfhSize, std::numeric_limits<float>::quiet_NaN());
            continue;
          }
          if (!cache.load(p, neighbors)) neighbors_of(p, neighbors);
          if (neighbors.size() < 2) {
            ++block_isolated;  // stays all zero, as in PCL
            continue;
          }
          weight_spfh(cloud, p, spfh, spfh_sums, neighbors, out);
          if (options.fpfh_variant == FpfhVariant::kWithOwnSpfh)
            for (int b = 0; b < kFpfhSize; ++b) out[b] += spfh[p * kFpfhSize + b];
          ++block_computed;
        }
        computed += block_computed, isolated += block_isolated;
        progress.add(last - first);
      });
  throw_if_stopped(stop, "FPFH");
  progress.finish();
  if (stats) *stats = FeatureStats{computed.load(), isolated.load(), n - computed - isolated};
  return Descriptors(kFpfhSize, std::move(fpfh));
}

}  // namespace primlabel
