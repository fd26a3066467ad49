// Point Feature Histograms (Rusu et al. 2008), computed as PCL 1.13's PFHEstimation does: every
// pair of points in the neighbourhood (the query included) adds 100 / (k (k - 1) / 2) to one of
// 5 x 5 x 5 bins indexed by (alpha, phi, theta). O(k^2) per point: kept for the paper's
// comparison with FPFH.

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

constexpr int kSplit = kPfhBinsPerFeature;

struct PfhScratch {
  detail::PairTargets targets;
  std::vector<std::uint8_t> alpha, phi, theta;
};

void compute_point_pfh(const PointCloud& cloud, const NeighborList& neighbors, PfhScratch& scratch,
                       float* pfh) {
  const std::size_t k = neighbors.size();
  scratch.targets.clear();
  for (std::uint32_t q : neighbors.indices) scratch.targets.push(cloud.xyz[q], cloud.normals[q]);
  scratch.alpha.resize(k), scratch.phi.resize(k), scratch.theta.resize(k);
  std::vector<std::uint32_t> counts(kPfhSize, 0);
  // Pairs (i, j < i) with point i first, in PCL's order.
  for (std::size_t i = 1; i < k; ++i) {
    const std::uint32_t a = neighbors.indices[i];
    detail::pair_bins_batch(cloud.xyz[a], cloud.normals[a], scratch.targets, i, kSplit,
                            scratch.alpha.data(), scratch.phi.data(), scratch.theta.data());
    for (std::size_t j = 0; j < i; ++j)
      ++counts[scratch.alpha[j] + kSplit * scratch.phi[j] + kSplit * kSplit * scratch.theta[j]];
  }
  // Repeated float additions, not count * increment: the rounding then matches PCL's.
  const float increment = 100.0f / static_cast<float>(k * (k - 1) / 2);
  for (int b = 0; b < kPfhSize; ++b)
    for (std::uint32_t c = 0; c < counts[b]; ++c) pfh[b] += increment;
}

}  // namespace

Descriptors compute_pfh(const PointCloud& cloud, const FeatureOptions& options,
                        const RunContext& context, const FeatureExtras& extras) {
  FeatureStats* stats = extras.stats;
  const std::stop_token& stop = context.stop;
  if (!options.neighborhood.valid())
    throw std::invalid_argument("PFH: invalid neighbourhood " + options.neighborhood.describe());
  const std::vector<char> usable = detail::usable_points(cloud, "PFH");
  std::unique_ptr<NeighborSearch> owned;
  const NeighborSearch& index = detail::ensure_search(cloud, extras.search, owned, stop);

  const std::size_t n = cloud.size();
  std::vector<float> pfh;
  detail::assign_checked(pfh, n * kPfhSize, 0.0f, stop, "PFH");
  std::atomic<std::size_t> computed{0}, isolated{0};
  detail::ProgressCounter progress(context.progress, n);
  constexpr std::size_t kBlock = 64;
  const auto blocks = static_cast<std::ptrdiff_t>((n + kBlock - 1) / kBlock);
  struct Scratch {
    NeighborList neighbors;
    PfhScratch pairs;
  };
  const auto make_scratch = [] { return Scratch(); };
  detail::for_each_block(
      blocks, context, make_scratch, [&](Scratch& scratch, std::ptrdiff_t block) {
        std::size_t block_computed = 0, block_isolated = 0;
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        for (std::size_t p = first; p < last; ++p) {
          if (stop.stop_requested()) return;  // per point: O(k^2) each
          float* out = &pfh[p * kPfhSize];
          if (!usable[p]) {
            std::fill(out, out + kPfhSize, std::numeric_limits<float>::quiet_NaN());
            continue;
          }
          // Pair order decides which point is "first" only in exact ties; sorted lists match
          // PCL's.
          detail::usable_neighbors(index, cloud, usable, p, options.neighborhood, true,
                                   scratch.neighbors);
          if (scratch.neighbors.size() >= 2) {
            compute_point_pfh(cloud, scratch.neighbors, scratch.pairs, out);
            ++block_computed;
          } else {
            ++block_isolated;  // stays all zero
          }
        }
        computed += block_computed, isolated += block_isolated;
        progress.add(last - first);
      });
  throw_if_stopped(stop, "PFH");
  progress.finish();
  if (stats) *stats = FeatureStats{computed.load(), isolated.load(), n - computed - isolated};
  return Descriptors(kPfhSize, std::move(pfh));
}

}  // namespace primlabel
