// Point Feature Histograms (Rusu et al. 2008), computed as PCL 1.13's PFHEstimation does: every
// pair of points in the neighbourhood (the query included) adds 100 / (k (k - 1) / 2) to one of
// 5 x 5 x 5 bins indexed by (alpha, phi, theta). O(k^2) per point: kept for the paper's
// comparison with FPFH.

#include <limits>

#include "feature_neighborhood.hpp"
#include "pair_features_inline.hpp"
#include "parallel.hpp"
#include "primlabel/core/features.hpp"

namespace primlabel {

namespace {

constexpr int kSplit = kPfhBinsPerFeature;

void compute_point_pfh(const PointCloud& cloud, const NeighborList& neighbors, float* pfh) {
  const std::size_t k = neighbors.size();
  const float increment = 100.0f / static_cast<float>(k * (k - 1) / 2);
  for (std::size_t i = 0; i < k; ++i) {
    const std::uint32_t a = neighbors.indices[i];
    for (std::size_t j = 0; j < i; ++j) {
      const std::uint32_t b = neighbors.indices[j];
      detail::PairFeatures f;
      detail::pair_features(cloud.xyz[a], cloud.normals[a], cloud.xyz[b], cloud.normals[b], f);
      const int bin = detail::angle_bin(f.alpha, kSplit) +
                      kSplit * detail::cosine_bin(f.phi, kSplit) +
                      kSplit * kSplit * detail::cosine_bin(f.theta, kSplit);
      pfh[bin] += increment;
    }
  }
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
  std::size_t computed = 0;
  detail::ProgressCounter progress(options.progress, n);
#pragma omp parallel num_threads(detail::resolve_threads(options.threads)) reduction(+ : computed)
  {
    NeighborList neighbors;
#pragma omp for schedule(dynamic, 64)
    for (std::ptrdiff_t p = 0; p < count; ++p) {
      float* out = &pfh[p * kPfhSize];
      bool ok = false;
      if (usable[p]) {
        // Pair order decides which point is "first" only in exact ties; sorted lists match PCL's.
        detail::usable_neighbors(index, cloud, usable, p, options.neighborhood, true, neighbors);
        if (neighbors.size() >= 2) {
          compute_point_pfh(cloud, neighbors, out);
          ok = true;
        }
      }
      if (ok)
        ++computed;
      else
        std::fill(out, out + kPfhSize, std::numeric_limits<float>::quiet_NaN());
      if ((p & 63) == 63) progress.add(64);
    }
  }
  progress.finish();
  if (stats) *stats = FeatureStats{computed, n - computed};
  return pfh;
}

}  // namespace primlabel
