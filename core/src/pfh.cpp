// Point Feature Histograms (Rusu et al. 2008), computed as PCL 1.13's PFHEstimation does: every
// pair of points in the neighbourhood (the query included) adds 100 / (k (k - 1) / 2) to one of
// 5 x 5 x 5 bins indexed by (alpha, phi, theta). O(k^2) per point: kept for the paper's
// comparison with FPFH.

#include <limits>

#include "feature_neighborhood.hpp"
#include "pair_bins_batch.hpp"
#include "parallel.hpp"
#include "primlabel/core/cancellation.hpp"
#include "primlabel/core/features.hpp"

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

std::vector<float> compute_pfh(const PointCloud& cloud, const FeatureOptions& options,
                               FeatureStats* stats, const NeighborSearch* search) {
  if (!options.neighborhood.valid())
    throw std::invalid_argument("PFH: invalid neighbourhood " + options.neighborhood.describe());
  const std::vector<char> usable = detail::usable_points(cloud, "PFH");
  std::unique_ptr<NeighborSearch> owned;
  const NeighborSearch& index = detail::ensure_search(cloud, search, owned);

  const std::size_t n = cloud.size();
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(n);
  std::vector<float> pfh(n * kPfhSize, 0.0f);
  std::size_t computed = 0, isolated = 0;
  detail::ProgressCounter progress(options.progress, n);
#pragma omp parallel num_threads(detail::resolve_threads(options.threads)) \
    reduction(+ : computed, isolated)
  {
    NeighborList neighbors;
    PfhScratch scratch;
    bool stopped = false;  // per thread: once cancelled, the remaining points are skipped
#pragma omp for schedule(dynamic, 64)
    for (std::ptrdiff_t p = 0; p < count; ++p) {
      if ((p & 63) == 0) stopped = stopped || options.stop.stop_requested();
      if (stopped) continue;
      float* out = &pfh[p * kPfhSize];
      if (!usable[p]) {
        std::fill(out, out + kPfhSize, std::numeric_limits<float>::quiet_NaN());
      } else {
        // Pair order decides which point is "first" only in exact ties; sorted lists match PCL's.
        detail::usable_neighbors(index, cloud, usable, p, options.neighborhood, true, neighbors);
        if (neighbors.size() >= 2) {
          compute_point_pfh(cloud, neighbors, scratch, out);
          ++computed;
        } else {
          ++isolated;  // stays all zero
        }
      }
      if ((p & 63) == 63) progress.add(64);
    }
  }
  throw_if_stopped(options.stop, "PFH");
  progress.finish();
  if (stats) *stats = FeatureStats{computed, isolated, n - computed - isolated};
  return pfh;
}

}  // namespace primlabel
