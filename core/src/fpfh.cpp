// Fast Point Feature Histograms (Rusu et al. 2009), computed as PCL 1.13's FPFHEstimation does:
//   1. SPFH(p): for each neighbour q != p, the pair features (alpha, phi, theta) are binned into
//      three 11-bin histograms, each pair adding 100 / (k - 1).
//   2. FPFH(p) = sum over neighbours q at squared distance d > 0 of SPFH(q) / d, each 11-bin
//      sub-histogram then scaled to sum to 100. The paper's variant adds SPFH(p) afterwards.
// SPFHs are stored row-major (one contiguous 33-float row per point) so pass 2 reads each
// neighbour's signature with one cache-friendly access.

#include <limits>

#include "feature_neighborhood.hpp"
#include "pair_features_inline.hpp"
#include "parallel.hpp"
#include "primlabel/core/features.hpp"

namespace primlabel {

namespace {

constexpr int kBins = kFpfhBinsPerFeature;

void compute_spfh(const PointCloud& cloud, std::size_t p, const NeighborList& neighbors,
                  float* spfh) {
  const float increment = 100.0f / static_cast<float>(neighbors.size() - 1);
  const Vec3f& p1 = cloud.xyz[p];
  const Vec3f& n1 = cloud.normals[p];
  for (std::uint32_t q : neighbors.indices) {
    if (q == p) continue;
    detail::PairFeatures f;
    // A failed pair (coincident points) still counts, with zero features: PCL does the same.
    detail::pair_features(p1, n1, cloud.xyz[q], cloud.normals[q], f);
    spfh[detail::angle_bin(f.alpha, kBins)] += increment;
    spfh[kBins + detail::cosine_bin(f.phi, kBins)] += increment;
    spfh[2 * kBins + detail::cosine_bin(f.theta, kBins)] += increment;
  }
}

void weight_spfh(const std::vector<float>& spfh, const NeighborList& neighbors, float* fpfh) {
  double sum[3] = {0.0, 0.0, 0.0};
  for (std::size_t j = 0; j < neighbors.size(); ++j) {
    if (neighbors.sq_dists[j] == 0.0f) continue;  // the point itself (and exact duplicates)
    const float weight = 1.0f / neighbors.sq_dists[j];
    const float* row = spfh.data() + std::size_t(neighbors.indices[j]) * kFpfhSize;
    for (int b = 0; b < kFpfhSize; ++b) {
      const float value = row[b] * weight;
      sum[b / kBins] += value;
      fpfh[b] += value;
    }
  }
  for (int s = 0; s < 3; ++s) {
    const double scale = sum[s] != 0.0 ? 100.0 / sum[s] : 0.0;  // sub-histogram sums to 100
    for (int b = s * kBins; b < (s + 1) * kBins; ++b) fpfh[b] = static_cast<float>(fpfh[b] * scale);
  }
}

}  // namespace

std::vector<float> compute_fpfh(const PointCloud& cloud, const FeatureOptions& options,
                                FeatureStats* stats, const NeighborSearch* search) {
  if (!options.neighborhood.valid())
    throw std::invalid_argument("FPFH: invalid neighbourhood " + options.neighborhood.describe());
  const std::vector<char> usable = detail::usable_points(cloud, "FPFH");
  std::unique_ptr<NeighborSearch> owned;
  const NeighborSearch& index = detail::ensure_search(cloud, search, owned);

  const std::size_t n = cloud.size();
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(n);
  const int threads = detail::resolve_threads(options.threads);
  // Radius neighbourhoods need no order: every sum below is order-independent up to rounding,
  // and tree order is itself deterministic.
  const bool sorted = false;

  std::vector<float> spfh(n * kFpfhSize, 0.0f);
  detail::ProgressCounter progress(options.progress, 2 * n);
#pragma omp parallel num_threads(threads)
  {
    NeighborList neighbors;
#pragma omp for schedule(dynamic, 256)
    for (std::ptrdiff_t p = 0; p < count; ++p) {
      if (usable[p]) {
        detail::usable_neighbors(index, cloud, usable, p, options.neighborhood, sorted, neighbors);
        if (neighbors.size() >= 2) compute_spfh(cloud, p, neighbors, &spfh[p * kFpfhSize]);
      }
      if ((p & 255) == 255) progress.add(256);
    }
  }

  std::vector<float> fpfh(n * kFpfhSize, 0.0f);
  std::size_t computed = 0;
#pragma omp parallel num_threads(threads) reduction(+ : computed)
  {
    NeighborList neighbors;
#pragma omp for schedule(dynamic, 256)
    for (std::ptrdiff_t p = 0; p < count; ++p) {
      float* out = &fpfh[p * kFpfhSize];
      bool ok = false;
      if (usable[p]) {
        detail::usable_neighbors(index, cloud, usable, p, options.neighborhood, sorted, neighbors);
        if (neighbors.size() >= 2) {
          weight_spfh(spfh, neighbors, out);
          if (options.fpfh_variant == FpfhVariant::kWithOwnSpfh)
            for (int b = 0; b < kFpfhSize; ++b) out[b] += spfh[p * kFpfhSize + b];
          ok = true;
        }
      }
      if (ok)
        ++computed;
      else
        std::fill(out, out + kFpfhSize, std::numeric_limits<float>::quiet_NaN());
      if ((p & 255) == 255) progress.add(256);
    }
  }
  progress.finish();
  if (stats) *stats = FeatureStats{computed, n - computed};
  return fpfh;
}

}  // namespace primlabel
