// The vectorised pair kernels (AVX2 and SSE2) must give exactly the bins of the scalar,
// PCL-identical path, for every input: random pairs, and pairs built to hit its fallbacks
// (axis-aligned normals with signed zeros, exact and near ties of the source choice, angles on bin
// boundaries).

#include <gtest/gtest.h>

#include <random>

#include "pair_bins_batch.hpp"
#include "pair_features_inline.hpp"

namespace primlabel::detail {
namespace {

struct Pair {
  Vec3f p1, n1, p2, n2;
};

std::size_t count_mismatches(const std::vector<Pair>& pairs, int bins) {
  std::size_t mismatches = 0;
  std::uint8_t alpha[1], phi[1], theta[1];
  for (const Pair& pair : pairs) {
    PairTargets targets;
    // Twelve copies: the first eight go through the AVX2 lanes where the CPU has them, the last
    // four through the SSE2 lanes (all twelve through SSE2 elsewhere), none through the tail.
    constexpr int kLanes = 12;
    for (int lane = 0; lane < kLanes; ++lane) targets.push(pair.p2, pair.n2);
    std::uint8_t a[kLanes], f[kLanes], t[kLanes];
    pair_bins_batch(pair.p1, pair.n1, targets, kLanes, bins, a, f, t);
    PairFeatures exact;
    pair_features(pair.p1, pair.n1, pair.p2, pair.n2, exact);
    alpha[0] = static_cast<std::uint8_t>(angle_bin(exact.alpha, bins));
    phi[0] = static_cast<std::uint8_t>(cosine_bin(exact.phi, bins));
    theta[0] = static_cast<std::uint8_t>(cosine_bin(exact.theta, bins));
    for (int lane = 0; lane < kLanes; ++lane)
      mismatches += (a[lane] != alpha[0]) + (f[lane] != phi[0]) + (t[lane] != theta[0]);
  }
  return mismatches;
}

Vec3f random_unit(std::mt19937& rng) {
  std::normal_distribution<float> g;
  Vec3f v(g(rng), g(rng), g(rng));
  return v.normalized();
}

TEST(PairBinsBatch, RandomPairsMatchTheExactPath) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.05f, 0.05f);
  std::vector<Pair> pairs;
  for (int i = 0; i < 400000; ++i)
    pairs.push_back({Vec3f(u(rng), u(rng), u(rng)), random_unit(rng), Vec3f(u(rng), u(rng), u(rng)),
                     random_unit(rng)});
  EXPECT_EQ(count_mismatches(pairs, 11), 0u);
  EXPECT_EQ(count_mismatches(pairs, 5), 0u);
}

TEST(PairBinsBatch, AdversarialPairsMatchTheExactPath) {
  // Grid positions and normals from axis and diagonal directions with both zero signs: exact
  // ties of |cos|, atan2 of signed zeros, cosines of exactly 0 and +-1, coincident points.
  std::vector<Vec3f> normals;
  for (float x : {-1.0f, -0.0f, 0.0f, 1.0f})
    for (float y : {-1.0f, -0.0f, 0.0f, 1.0f})
      for (float z : {-1.0f, -0.0f, 0.0f, 1.0f}) {
        Vec3f n(x, y, z);
        if (n.norm() > 0) normals.push_back(n / n.norm());
      }
  std::vector<Vec3f> positions;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z) positions.emplace_back(0.01f * x, 0.01f * y, 0.01f * z);
  std::vector<Pair> pairs;
  std::mt19937 rng(11);
  for (const Vec3f& n1 : normals)
    for (const Vec3f& n2 : normals)
      for (int k = 0; k < 12; ++k)
        pairs.push_back({Vec3f::Zero(), n1, positions[rng() % positions.size()], n2});
  // Angles exactly on the alpha bin boundaries of 11 and 5 bins.
  for (int bins : {5, 11})
    for (int b = 0; b <= bins; ++b) {
      const double angle = -M_PI + 2.0 * M_PI * b / bins;
      pairs.push_back(
          {Vec3f::Zero(), Vec3f(0, 0, 1), Vec3f(1, 0, 0),
           Vec3f(float(std::sin(angle)) * 0.1f, 0, float(std::cos(angle))).normalized()});
      pairs.push_back({Vec3f::Zero(), Vec3f(0, 0, 1), Vec3f(1, 0, 0),
                       Vec3f(0, float(std::sin(angle)), float(std::cos(angle)))});
    }
  EXPECT_EQ(count_mismatches(pairs, 11), 0u);
  EXPECT_EQ(count_mismatches(pairs, 5), 0u);
}

TEST(PairBinsBatch, ScalarTailAndPrefixCounts) {
  std::mt19937 rng(3);
  PairTargets targets;
  // 15 of 16: eight wide, four wide and a scalar tail of three, the 16th untouched.
  for (int i = 0; i < 16; ++i) targets.push(Vec3f(0.01f * i, 0.02f, -0.01f * i), random_unit(rng));
  const Vec3f p1(0.001f, 0, 0), n1 = random_unit(rng);
  std::vector<std::uint8_t> a(16, 99), f(16, 99), t(16, 99);
  pair_bins_batch(p1, n1, targets, 15, 11, a.data(), f.data(), t.data());
  EXPECT_EQ(a[15], 99);  // beyond the prefix: untouched
  for (int j = 0; j < 15; ++j) {
    PairFeatures exact;
    pair_features(p1, n1, Vec3f(targets.x[j], targets.y[j], targets.z[j]),
                  Vec3f(targets.nx[j], targets.ny[j], targets.nz[j]), exact);
    EXPECT_EQ(a[j], angle_bin(exact.alpha, 11));
    EXPECT_EQ(f[j], cosine_bin(exact.phi, 11));
    EXPECT_EQ(t[j], cosine_bin(exact.theta, 11));
  }
}

}  // namespace
}  // namespace primlabel::detail
