#pragma once
// Point Feature Histograms (Rusu et al.): FPFH (33 bins) and PFH (125 bins), computed exactly as
// PCL 1.13 computes them so descriptors are interchangeable with PCL's.
//
// Defined behaviour for bad input: a point with non-finite coordinates or normal gets an all-NaN
// descriptor. A point with no usable neighbour but itself gets an all-zero descriptor, as in PCL
// (every sub-histogram of a valid descriptor sums to 100, so it is easy to tell apart). Neighbours
// with non-finite normals are left out of every histogram (PCL would bin their NaN angles into
// bin 0).

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "primlabel/geometry/descriptors.hpp"
#include "primlabel/geometry/neighbor_lists.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/progress.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel {

inline constexpr int kFpfhBinsPerFeature = 11;
inline constexpr int kFpfhSize = 3 * kFpfhBinsPerFeature;  // 33
inline constexpr int kPfhBinsPerFeature = 5;
inline constexpr int kPfhSize = 125;  // 5^3

enum class FpfhVariant {
  kPcl,          // PCL: weighted sum of the neighbours' SPFHs only
  kWithOwnSpfh,  // the paper's formula as Open3D implements it: PCL's result + the point's own SPFH
};

// The descriptor's field name in written clouds: PCL's FPFHSignature33 is "fpfh" (rows sum to
// 300); the paper's variant is "fpfh_paper" (rows sum to 600), so no file passes one off as the
// other.
inline const char* fpfh_field_name(FpfhVariant variant) {
  return variant == FpfhVariant::kPcl ? "fpfh" : "fpfh_paper";
}

struct FeatureOptions {
  Neighborhood neighborhood = Neighborhood::Knn(10);
  FpfhVariant fpfh_variant = FpfhVariant::kPcl;
  // FPFH keeps each point's neighbour list between its two passes up to this many bytes (4 per
  // neighbour); points beyond it are searched twice. Results do not depend on it.
  std::size_t neighbor_cache_bytes = std::size_t(1) << 30;
  // FPFH only: when not empty (one entry per point), only the points marked non-zero are
  // described, bit for bit as without it; the others get NaN rows. The histograms of their
  // neighbours are computed, nothing further, so the cost follows the marked points.
  std::span<const std::uint8_t> wanted;
};

struct FeatureStats {
  std::size_t computed = 0;  // points with a histogram from at least one neighbour
  std::size_t isolated = 0;  // valid points with no neighbour: all-zero descriptor
  std::size_t nan = 0;       // invalid points or normals: NaN descriptor
};

// What a descriptor computation may be lent and where it reports; each part optional.
struct FeatureExtras {
  const NeighborSearch* search = nullptr;  // an index on cloud.xyz; built when null
  // FPFH: shared neighbour lists on cloud.xyz (see estimate_normals), used when the
  // neighbourhood is a radius within theirs.
  const NeighborLists* lists = nullptr;
  FeatureStats* stats = nullptr;  // filled when set
};

// cloud.size() x 33. Requires cloud.normals. Once context.stop is requested the remaining blocks
// of points are skipped and the function throws Cancelled; context.progress counts points (twice:
// both passes).
Descriptors compute_fpfh(const PointCloud& cloud, const FeatureOptions& options,
                         const RunContext& context = {}, const FeatureExtras& extras = {});

// cloud.size() x 125. Requires cloud.normals. context as for compute_fpfh; extras.lists unused.
Descriptors compute_pfh(const PointCloud& cloud, const FeatureOptions& options,
                        const RunContext& context = {}, const FeatureExtras& extras = {});

// The four pair features of (p1, n1) and (p2, n2) as pcl::computePairFeatures defines them.
// `valid` is false (and the features all zero, which is what PCL bins) for coincident points or a
// degenerate frame.
struct PairFeatures {
  float f1 = 0.0f;  // alpha: theta in the Darboux frame (atan2), [-pi, pi]
  float f2 = 0.0f;  // phi: cosine, v . n2
  float f3 = 0.0f;  // theta: cosine, u . (p2 - p1) / |p2 - p1|
  float f4 = 0.0f;  // distance |p2 - p1|
  bool valid = false;
};
PairFeatures compute_pair_features(const Vec3f& p1, const Vec3f& n1, const Vec3f& p2,
                                   const Vec3f& n2);

}  // namespace primlabel
