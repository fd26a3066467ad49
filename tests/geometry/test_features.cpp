#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>
#include <random>

#include "pair_features_inline.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/normals.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

// ---- pair features -----------------------------------------------------------------------------

TEST(PairFeatures, ParallelNormalsOnAPlane) {
  const PairFeatures f = compute_pair_features({0, 0, 0}, {0, 0, 1}, {2, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(f.valid);
  EXPECT_FLOAT_EQ(f.f4, 2.0f);
  EXPECT_FLOAT_EQ(f.f1, 0.0f);
  EXPECT_FLOAT_EQ(f.f2, 0.0f);
  EXPECT_FLOAT_EQ(f.f3, 0.0f);
}

TEST(PairFeatures, AlphaIsTheNormalsAngleInTheDarbouxFrame) {
  const float a = 0.3f;
  // n2 = (sin a, 0, cos a) is closer to the line than n1 = z, so p2 is the source: u = n2,
  // delta = -x, v = delta x u / |..| = y, w = u x v = (-cos a, 0, sin a); alpha = atan2(w.n1,
  // u.n1).
  const PairFeatures f =
      compute_pair_features({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {std::sin(a), 0, std::cos(a)});
  ASSERT_TRUE(f.valid);
  EXPECT_NEAR(f.f1, a, 1e-6f);
  EXPECT_NEAR(f.f2, 0.0f, 1e-7f);
  EXPECT_NEAR(f.f3, -std::sin(a), 1e-7f);
}

TEST(PairFeatures, SourceIsThePointWhoseNormalIsCloserToTheLine) {
  // n2 is nearly along the connecting line, n1 perpendicular to it: swapped, theta = -n2.x.
  const Vec3f n2 = Vec3f(1, 0, 0.5f).normalized();
  const PairFeatures f = compute_pair_features({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, n2);
  ASSERT_TRUE(f.valid);
  EXPECT_FLOAT_EQ(f.f3, -n2.x());
  // and the features do not depend on the order of the points
  const PairFeatures g = compute_pair_features({1, 0, 0}, n2, {0, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(g.valid);
  EXPECT_FLOAT_EQ(f.f1, g.f1);
  EXPECT_FLOAT_EQ(f.f2, g.f2);
  EXPECT_FLOAT_EQ(f.f3, g.f3);
}

TEST(PairFeatures, DegeneratePairsAreZero) {
  const PairFeatures f = compute_pair_features({1, 1, 1}, {0, 0, 1}, {1, 1, 1}, {0, 1, 0});
  EXPECT_FALSE(f.valid);
  EXPECT_EQ(f.f1 + f.f2 + f.f3 + f.f4, 0.0f);
  // Normal parallel to the connecting line: no Darboux frame.
  const PairFeatures g = compute_pair_features({0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {1, 0, 0});
  EXPECT_FALSE(g.valid);
  EXPECT_EQ(g.f1 + g.f2 + g.f3 + g.f4, 0.0f);
}

// The public struct carries exactly the features the histogram kernels bin (same arithmetic).
TEST(PairFeatures, TheStructHoldsTheKernelsFeaturesBitForBit) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int t = 0; t < 1000; ++t) {
    const Vec3f p1(u(rng), u(rng), u(rng)), p2(u(rng), u(rng), u(rng));
    const Vec3f n1 = Vec3f(u(rng), u(rng), u(rng)).normalized();
    const Vec3f n2 = Vec3f(u(rng), u(rng), u(rng)).normalized();
    detail::PairFeatures expected;
    const bool ok = detail::pair_features(p1, n1, p2, n2, expected);
    const PairFeatures f = compute_pair_features(p1, n1, p2, n2);
    EXPECT_EQ(f.valid, ok);
    EXPECT_EQ(std::memcmp(&f.f1, &expected.alpha, 4), 0);
    EXPECT_EQ(std::memcmp(&f.f2, &expected.phi, 4), 0);
    EXPECT_EQ(std::memcmp(&f.f3, &expected.theta, 4), 0);
    EXPECT_EQ(std::memcmp(&f.f4, &expected.dist, 4), 0);
  }
}

// ---- descriptors
// ---------------------------------------------------------------------------------

TEST(Descriptors, RowsSizeAndShapeChecks) {
  Descriptors d(3, {1, 2, 3, 4, 5, 6});
  EXPECT_EQ(d.size(), 2u);
  EXPECT_EQ(d.row(1)[0], 4.0f);
  EXPECT_EQ(d.row(1).size(), 3u);
  d.row(0)[2] = 9.0f;
  EXPECT_EQ(d.values[2], 9.0f);
  EXPECT_THROW(Descriptors(3, {1, 2}), std::invalid_argument);
  EXPECT_THROW(Descriptors(0, {}), std::invalid_argument);
  const Descriptors nan = Descriptors::filled(4, 33, NAN);
  EXPECT_EQ(nan.size(), 4u);
  EXPECT_TRUE(std::isnan(nan.row(3)[32]));
  EXPECT_EQ(Descriptors().size(), 0u);
}

// ---- conformance with PCL 1.13 on the Stanford bunny (reference fixtures made by PCL) ----------

class BunnyConformance : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string path = test::shared_data("pcl/bun0.pcd");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
    cloud_ = read_pcd(path);
    ASSERT_TRUE(cloud_.has_normals());
    ASSERT_EQ(cloud_.size(), 397u);
  }

  // Largest |ours - PCL| over every bin of every point; NaN must match NaN.
  float max_difference(const Descriptors& ours, int bins, const std::string& fixture) {
    EXPECT_EQ(ours.dim, bins);
    const auto reference = test::read_csv(test::test_data("reference/" + fixture));
    EXPECT_EQ(reference.size(), cloud_.size());
    float worst = 0.0f;
    for (std::size_t i = 0; i < reference.size(); ++i) {
      EXPECT_EQ(reference[i].size(), static_cast<std::size_t>(bins));
      for (int b = 0; b < bins; ++b) {
        const float mine = ours.row(i)[b], theirs = reference[i][b];
        if (std::isnan(mine) || std::isnan(theirs)) {
          EXPECT_EQ(std::isnan(mine), std::isnan(theirs)) << "point " << i << " bin " << b;
          continue;
        }
        worst = std::max(worst, std::abs(mine - theirs));
      }
    }
    return worst;
  }

  // FPFH / PFH of the bunny with this neighbourhood, against PCL's in `fixture`.
  float fpfh_difference(const Neighborhood& neighborhood, const std::string& fixture) {
    return max_difference(compute_fpfh(cloud_, with(neighborhood)), kFpfhSize, fixture);
  }
  float pfh_difference(const Neighborhood& neighborhood, const std::string& fixture) {
    return max_difference(compute_pfh(cloud_, with(neighborhood)), kPfhSize, fixture);
  }

  static FeatureOptions with(const Neighborhood& neighborhood) {
    FeatureOptions options;
    options.neighborhood = neighborhood;
    return options;
  }

  PointCloud cloud_;
};

TEST_F(BunnyConformance, FpfhK10) {
  EXPECT_LE(fpfh_difference(Neighborhood::Knn(10), "bun0_fpfh_k10.csv"), 1e-4f);
}

TEST_F(BunnyConformance, FpfhRadius001) {
  EXPECT_LE(fpfh_difference(Neighborhood::Radius(0.01f), "bun0_fpfh_r0.01.csv"), 1e-4f);
}

TEST_F(BunnyConformance, FpfhRadius002) {
  EXPECT_LE(fpfh_difference(Neighborhood::Radius(0.02f), "bun0_fpfh_r0.02.csv"), 1e-4f);
}

TEST_F(BunnyConformance, PfhK10) {
  EXPECT_LE(pfh_difference(Neighborhood::Knn(10), "bun0_pfh_k10.csv"), 1e-4f);
}

// ---- histogram properties ----------------------------------------------------------------------

PointCloud sphere_with_normals(int n, unsigned seed) {
  PointCloud cloud = test::sphere(Vec3f(0, 0, 1), 0.1f, n, 0.0005f, seed);
  NormalOptions options;
  options.neighborhood = Neighborhood::Knn(10);
  estimate_normals(cloud, options);
  return cloud;
}

float sub_sum(const Descriptors& h, std::size_t point, int sub) {
  const float* row = h.row(point).data() + sub * kFpfhBinsPerFeature;
  return std::accumulate(row, row + kFpfhBinsPerFeature, 0.0f);
}

TEST(Fpfh, SubHistogramsSumTo100AndThePaperVariantAddsTheOwnSpfh) {
  PointCloud cloud = sphere_with_normals(3000, 5);
  FeatureOptions options;
  options.neighborhood = Neighborhood::Radius(0.02f);
  FeatureStats stats;
  const auto pcl = compute_fpfh(cloud, options, {}, {.stats = &stats});
  EXPECT_EQ(stats.computed, cloud.size());
  EXPECT_EQ(stats.nan, 0u);
  options.fpfh_variant = FpfhVariant::kWithOwnSpfh;
  const auto paper = compute_fpfh(cloud, options);
  for (std::size_t i = 0; i < cloud.size(); i += 37)
    for (int s = 0; s < 3; ++s) {
      ASSERT_NEAR(sub_sum(pcl, i, s), 100.0f, 1e-3f);
      ASSERT_NEAR(sub_sum(paper, i, s), 200.0f, 2e-3f);  // own SPFH also sums to 100
    }
}

TEST(Fpfh, PlaneAndSphereDiffer) {
  // The descriptor must tell a plane from a curved surface: plane pairs all land in the
  // middle bins (alpha = phi = theta = 0), sphere pairs spread out.
  PointCloud plane = test::plane_grid(0, 0, 0.1f, 0.005f);
  plane.viewpoint.origin = Vec3f(0, 0, 1);
  NormalOptions normal_options;
  normal_options.neighborhood = Neighborhood::Radius(0.012f);
  estimate_normals(plane, normal_options);
  FeatureOptions options;
  options.neighborhood = Neighborhood::Radius(0.02f);
  const auto h = compute_fpfh(plane, options);
  const std::size_t center = plane.size() / 2;
  EXPECT_NEAR(h.row(center)[5], 100.0f, 1e-3f);
  EXPECT_NEAR(h.row(center)[11 + 5], 100.0f, 1e-3f);
  EXPECT_NEAR(h.row(center)[22 + 5], 100.0f, 1e-3f);

  PointCloud ball = sphere_with_normals(3000, 9);
  const auto hb = compute_fpfh(ball, options);
  EXPECT_LT(hb.row(0)[22 + 5], 95.0f);
}

TEST(Features, InvalidPointsAndNormalsAreNaNAndLeftOutOfNeighbourhoods) {
  PointCloud cloud = sphere_with_normals(2000, 11);
  const std::size_t broken_normal = 100, broken_point = 200;
  cloud.normals[broken_normal] = Vec3f::Constant(NAN);
  cloud.xyz[broken_point] = Vec3f::Constant(NAN);
  cloud.xyz.push_back(Vec3f(9, 9, 9));  // isolated: no neighbour but itself
  cloud.normals.push_back(Vec3f(0, 0, 1));
  FeatureOptions options;
  options.neighborhood = Neighborhood::Radius(0.02f);
  FeatureStats stats;
  const auto with_gaps = compute_fpfh(cloud, options, {}, {.stats = &stats});
  EXPECT_EQ(stats.nan, 2u);
  EXPECT_EQ(stats.isolated, 1u);
  EXPECT_EQ(stats.computed, cloud.size() - 3);
  for (std::size_t p : {broken_normal, broken_point})
    for (int b = 0; b < kFpfhSize; ++b) EXPECT_TRUE(std::isnan(with_gaps.row(p)[b])) << p;
  const std::size_t lonely = cloud.size() - 1;  // like PCL: all zero
  for (int b = 0; b < kFpfhSize; ++b) EXPECT_EQ(with_gaps.row(lonely)[b], 0.0f);

  // A neighbour without a normal counts as absent: same descriptors as with it removed.
  PointCloud without = cloud;
  without.xyz[broken_normal] = Vec3f::Constant(NAN);
  const auto removed = compute_fpfh(without, options);
  for (std::size_t i = 0; i < cloud.size() - 1; ++i) {
    if (i == broken_normal || i == broken_point) continue;
    for (int b = 0; b < kFpfhSize; ++b) ASSERT_NEAR(with_gaps.row(i)[b], removed.row(i)[b], 1e-4f);
  }
  FeatureStats pfh_stats;
  const auto pfh = compute_pfh(cloud, options, {}, {.stats = &pfh_stats});
  EXPECT_EQ(pfh_stats.nan, 2u);
  EXPECT_EQ(pfh_stats.isolated, 1u);
  EXPECT_TRUE(std::isnan(pfh.row(broken_normal)[0]));
  for (int b = 0; b < kPfhSize; ++b) EXPECT_EQ(pfh.row(cloud.size() - 1)[b], 0.0f);
}

TEST(Features, RejectCloudsWithoutNormalsAndBadNeighbourhoods) {
  PointCloud cloud = test::random_box(10, 1.0f, 1);
  FeatureOptions options;
  EXPECT_THROW(compute_fpfh(cloud, options), std::invalid_argument);
  EXPECT_THROW(compute_pfh(cloud, options), std::invalid_argument);
  cloud.normals.assign(cloud.size(), Vec3f(0, 0, 1));
  options.neighborhood = Neighborhood::Knn(0);
  EXPECT_THROW(compute_fpfh(cloud, options), std::invalid_argument);
  PointCloud empty;
  options.neighborhood = Neighborhood::Knn(5);
  EXPECT_TRUE(compute_fpfh(empty, options).empty());
}

// FPFH straight from its definition: every ordered pair computed by the scalar pair features,
// SPFH bins as repeated additions, neighbours weighted in the search's order.
Descriptors reference_fpfh(const PointCloud& cloud, const Neighborhood& hood) {
  const NeighborSearch search(cloud.xyz);
  const std::size_t n = cloud.size();
  const auto usable = [&](std::size_t i) {
    return is_finite(cloud.xyz[i]) && is_finite(cloud.normals[i]);
  };
  std::vector<std::vector<std::uint32_t>> lists(n);
  for (std::size_t p = 0; p < n; ++p) {
    if (!usable(p)) continue;
    NeighborList found;
    search.find(cloud.xyz[p], hood, found, /*sorted=*/false);
    for (std::uint32_t q : found.indices)
      if (usable(q)) lists[p].push_back(q);
  }
  constexpr int kBins = kFpfhBinsPerFeature;
  std::vector<float> spfh(n * kFpfhSize, 0.0f);
  std::vector<double> sums(n * 3, 0.0);
  for (std::size_t p = 0; p < n; ++p) {
    if (lists[p].size() < 2) continue;
    int counts[kFpfhSize] = {};
    for (std::uint32_t q : lists[p]) {
      if (q == p) continue;
      detail::PairFeatures f;
      detail::pair_features(cloud.xyz[p], cloud.normals[p], cloud.xyz[q], cloud.normals[q], f);
      ++counts[detail::angle_bin(f.alpha, kBins)];
      ++counts[kBins + detail::cosine_bin(f.phi, kBins)];
      ++counts[2 * kBins + detail::cosine_bin(f.theta, kBins)];
    }
    const float increment = 100.0f / static_cast<float>(lists[p].size() - 1);
    for (int b = 0; b < kFpfhSize; ++b) {
      float value = 0.0f;
      for (int c = 0; c < counts[b]; ++c) value += increment;
      spfh[p * kFpfhSize + b] = value;
      sums[3 * p + b / kBins] += value;
    }
  }
  Descriptors out(kFpfhSize, std::vector<float>(n * kFpfhSize, 0.0f));
  for (std::size_t p = 0; p < n; ++p) {
    float* row = out.values.data() + p * kFpfhSize;
    if (!usable(p)) {
      std::fill(row, row + kFpfhSize, std::numeric_limits<float>::quiet_NaN());
      continue;
    }
    if (lists[p].size() < 2) continue;
    float accumulated[kFpfhSize] = {};
    double sum[3] = {};
    for (std::uint32_t q : lists[p]) {
      const Vec3f& a = cloud.xyz[p];
      const Vec3f& b = cloud.xyz[q];
      const float dx = a.x() - b.x(), dy = a.y() - b.y(), dz = a.z() - b.z();
      const float sq = (dx * dx + dy * dy) + dz * dz;
      if (sq == 0.0f) continue;
      const float weight = 1.0f / sq;
      for (int k = 0; k < kFpfhSize; ++k) accumulated[k] += spfh[q * kFpfhSize + k] * weight;
      for (int s = 0; s < 3; ++s) sum[s] += sums[3 * q + s] * weight;
    }
    for (int s = 0; s < 3; ++s) {
      const double scale = sum[s] != 0.0 ? 100.0 / sum[s] : 0.0;
      for (int k = s * kBins; k < (s + 1) * kBins; ++k)
        row[k] = static_cast<float>(accumulated[k] * scale);
    }
  }
  return out;
}

// compute_fpfh computes each pair of a radius neighbourhood once and counts it for both ends;
// that must give the definition's bits where the two ends disagree too: an exact plane (the
// angles to the line tie), coincident points, points without a normal, lists cut by a cap.
TEST(Fpfh, PairsComputedOnceGiveTheDefinitionsBits) {
  PointCloud cloud;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) {
      cloud.xyz.emplace_back(0.004f * i, 0.004f * j, 0.0f);
      cloud.normals.emplace_back(0.0f, 0.0f, 1.0f);
    }
  const PointCloud ball = sphere_with_normals(1500, 7);
  for (std::size_t i = 0; i < ball.size(); ++i) {
    cloud.xyz.push_back(ball.xyz[i] + Vec3f(0.05f, 0.05f, -0.9f));
    cloud.normals.push_back(ball.normals[i]);
  }
  for (std::size_t i = 0; i < 40; ++i) {  // duplicates, some with another normal
    cloud.xyz.push_back(cloud.xyz[i * 37]);
    cloud.normals.push_back(i % 2 ? cloud.normals[i * 37] : Vec3f(0.0f, 0.6f, 0.8f));
  }
  // Pairs whose angles to the line tie exactly while their normals differ: each end is its own
  // source, and theta changes sign.
  for (int k = 0; k < 8; ++k) {
    const Vec3f p(1.0f + 0.1f * k, 0.0f, 0.0f);
    cloud.xyz.push_back(p), cloud.normals.emplace_back(0.6f, 0.8f, 0.0f);
    cloud.xyz.push_back(p + Vec3f(0.004f, 0.0f, 0.0f)),
        cloud.normals.emplace_back(0.6f, 0.0f, 0.8f);
  }
  for (std::size_t i = 5; i < cloud.size(); i += 97)
    cloud.normals[i] = Vec3f::Constant(std::numeric_limits<float>::quiet_NaN());
  cloud.curvature.assign(cloud.size(), 0.0f);

  for (const Neighborhood& hood :
       {Neighborhood::Radius(0.013f), Neighborhood::Hybrid(0.013f, 20)}) {
    const Descriptors expected = reference_fpfh(cloud, hood);
    for (int threads : {1, 2}) {
      FeatureOptions options;
      options.neighborhood = hood;
      const Descriptors got = compute_fpfh(cloud, options, RunContext{threads});
      ASSERT_EQ(got.values.size(), expected.values.size());
      for (std::size_t i = 0; i < got.values.size(); ++i) {
        const float a = got.values[i], b = expected.values[i];
        ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0)
            << hood.describe() << ", " << threads << " threads: point " << i / kFpfhSize << " bin "
            << i % kFpfhSize << ": " << a << " vs " << b;
      }
    }
  }
}

// Describing some points only gives those points the bits of the whole computation (with the
// cloud's neighbour index and with shared lists) and the others NaN rows.
TEST(Fpfh, WantedPointsGetTheWholeComputationsBitsAndTheOthersNaN) {
  PointCloud cloud = sphere_with_normals(6000, 21);
  for (std::size_t i = 3; i < cloud.size(); i += 211)
    cloud.normals[i] = Vec3f::Constant(std::numeric_limits<float>::quiet_NaN());
  std::vector<std::uint8_t> wanted(cloud.size(), 0);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    wanted[i] = cloud.xyz[i].z() > 1.03f || i % 17 == 0;  // a cap and a scatter
  const NeighborSearch search(cloud.xyz);
  const NeighborLists lists(cloud.xyz, search, Neighborhood::Radius(0.015f), std::size_t(1) << 28);
  for (const Neighborhood& hood :
       {Neighborhood::Radius(0.012f), Neighborhood::Hybrid(0.012f, 30), Neighborhood::Knn(12)}) {
    FeatureOptions options;
    options.neighborhood = hood;
    for (const NeighborLists* shared : {static_cast<const NeighborLists*>(nullptr), &lists}) {
      const Descriptors all =
          compute_fpfh(cloud, options, RunContext{2}, {.search = &search, .lists = shared});
      options.wanted = wanted;
      FeatureStats stats;
      const Descriptors some = compute_fpfh(cloud, options, RunContext{2},
                                            {.search = &search, .lists = shared, .stats = &stats});
      options.wanted = {};
      std::size_t described = 0;
      for (std::size_t p = 0; p < cloud.size(); ++p) {
        const std::span<const float> got = some.row(p), full = all.row(p);
        if (!wanted[p]) {
          ASSERT_TRUE(std::isnan(got[0])) << hood.describe() << ": point " << p;
          continue;
        }
        described += std::isfinite(full[0]) ? 1 : 0;
        ASSERT_EQ(0, std::memcmp(got.data(), full.data(), kFpfhSize * sizeof(float)))
            << hood.describe() << (shared ? " (shared lists)" : "") << ": point " << p;
      }
      EXPECT_EQ(stats.computed + stats.isolated, described);
    }
  }
  FeatureOptions wrong;
  wrong.neighborhood = Neighborhood::Radius(0.012f);
  wrong.wanted = std::span<const std::uint8_t>(wanted.data(), wanted.size() - 1);
  EXPECT_THROW(compute_fpfh(cloud, wrong), std::invalid_argument);
}

TEST(Features, IdenticalForAnyThreadCount) {
  PointCloud cloud = sphere_with_normals(20000, 13);
  Descriptors fpfh_reference, pfh_reference;
  for (int threads : {1, 2, 3}) {
    FeatureOptions options;
    options.neighborhood = Neighborhood::Radius(0.012f);
    const RunContext context{threads};
    const auto fpfh = compute_fpfh(cloud, options, context);
    options.neighborhood = Neighborhood::Knn(8);
    const auto pfh = compute_pfh(cloud, options, context);
    if (fpfh_reference.empty()) {
      fpfh_reference = fpfh;
      pfh_reference = pfh;
      continue;
    }
    ASSERT_EQ(fpfh.values.size(), fpfh_reference.values.size());
    ASSERT_EQ(0, std::memcmp(fpfh.values.data(), fpfh_reference.values.data(),
                             fpfh.values.size() * sizeof(float)));
    ASSERT_EQ(0, std::memcmp(pfh.values.data(), pfh_reference.values.data(),
                             pfh.values.size() * sizeof(float)));
  }
}

}  // namespace
}  // namespace primlabel
