#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/normals.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

TEST(Normals, TiltedPlaneFacesTheViewpointWithZeroCurvature) {
  PointCloud cloud = test::plane_grid(0.2f, -0.1f, 0.5f, 0.02f);
  NormalOptions options;
  options.neighborhood = Neighborhood::Radius(0.05f);
  options.viewpoint = Vec3f(0, 0, 10);
  const NormalStats stats = estimate_normals(cloud, options);
  EXPECT_EQ(stats.estimated, cloud.size());
  const Vec3f expected = Vec3f(-0.2f, 0.1f, 1.0f).normalized();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_NEAR(cloud.normals[i].dot(expected), 1.0f, 1e-5f) << "point " << i;
    ASSERT_NEAR(cloud.curvature[i], 0.0f, 1e-6f);
  }
  // A viewpoint below the plane flips every normal.
  options.viewpoint = Vec3f(0, 0, -10);
  estimate_normals(cloud, options);
  for (const auto& n : cloud.normals) ASSERT_NEAR(n.dot(expected), -1.0f, 1e-5f);
}

TEST(Normals, SphereNormalsAreRadialAndCurved) {
  const Vec3f center(0.3f, -0.2f, 1.5f);
  PointCloud cloud = test::sphere(center, 0.1f, 4000);
  NormalOptions options;
  options.neighborhood = Neighborhood::Knn(12);
  options.viewpoint = center;  // from the inside: normals point inward
  estimate_normals(cloud, options);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vec3f inward = (center - cloud.xyz[i]).normalized();
    ASSERT_GT(cloud.normals[i].dot(inward), 0.995f) << "point " << i;
    ASSERT_GT(cloud.curvature[i], 0.0f);
    ASSERT_LT(cloud.curvature[i], 1.0f / 3.0f);
  }
}

TEST(Normals, DefaultViewpointIsTheCloudsSensorOrigin) {
  PointCloud cloud = test::plane_grid(0.0f, 0.0f, 0.2f, 0.02f);
  cloud.viewpoint.origin = Vec3f(0, 0, -3);
  NormalOptions options;
  options.neighborhood = Neighborhood::Knn(8);
  estimate_normals(cloud, options);
  for (const auto& n : cloud.normals) ASSERT_NEAR(n.z(), -1.0f, 1e-5f);
}

TEST(Normals, TooFewNeighboursAndInvalidPointsGiveNaNAndAreCounted) {
  PointCloud cloud;
  cloud.xyz = {{0, 0, 0},
               {0.01f, 0, 0},
               {0, 0.01f, 0},
               {0.01f, 0.01f, 0.001f},  // a patch
               {5, 5, 5},
               {5.01f, 5, 5},  // a pair
               {Vec3f::Constant(NAN)}};
  cloud.width = 7;
  NormalOptions options;
  options.neighborhood = Neighborhood::Radius(0.05f);
  const NormalStats stats = estimate_normals(cloud, options);
  EXPECT_EQ(stats.estimated, 4u);
  EXPECT_EQ(stats.too_few, 2u);
  EXPECT_EQ(stats.invalid_input, 1u);
  for (int i = 4; i < 7; ++i) {
    EXPECT_TRUE(std::isnan(cloud.normals[i].x())) << i;
    EXPECT_TRUE(std::isnan(cloud.curvature[i])) << i;
  }
  ASSERT_EQ(cloud.normals.size(), cloud.size());
}

TEST(Normals, CoincidentPointsHaveNoNormal) {
  PointCloud cloud;
  cloud.xyz.assign(5, Vec3f(1, 2, 3));
  cloud.width = 5;
  NormalOptions options;
  options.neighborhood = Neighborhood::Knn(5);
  const NormalStats stats = estimate_normals(cloud, options);
  EXPECT_EQ(stats.estimated, 0u);
  EXPECT_TRUE(std::isnan(cloud.normals[0].x()));
}

TEST(Normals, IdenticalForAnyThreadCount) {
  PointCloud cloud = test::sphere(Vec3f(0, 0, 1), 0.2f, 20000, 0.002f, 3);
  std::vector<Vec3f> reference;
  for (int threads : {1, 2, 3, 4}) {
    NormalOptions options;
    options.neighborhood = Neighborhood::Radius(0.02f);
    estimate_normals(cloud, options, RunContext{threads});
    if (reference.empty()) {
      reference = cloud.normals;
      continue;
    }
    ASSERT_EQ(0,
              std::memcmp(reference.data(), cloud.normals.data(), reference.size() * sizeof(Vec3f)))
        << threads << " threads";
  }
}

TEST(Normals, OnlyTheWantedPointsGetOneAndAllServeAsNeighbours) {
  PointCloud cloud = test::sphere(Vec3f(0, 0, 1), 0.2f, 5000, 0.002f, 3);
  NormalOptions options;
  options.neighborhood = Neighborhood::Radius(0.03f);
  estimate_normals(cloud, options);
  const std::vector<Vec3f> everyone = cloud.normals;
  std::vector<std::uint8_t> wanted(cloud.size(), 0);
  for (std::size_t i = 0; i < wanted.size(); i += 3) wanted[i] = 1;
  options.wanted = wanted;
  const NormalStats stats = estimate_normals(cloud, options, RunContext{2});
  EXPECT_EQ(stats.estimated, (cloud.size() + 2) / 3);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (wanted[i])
      EXPECT_EQ(cloud.normals[i], everyone[i]) << i;  // the same neighbours: the same normal
    else
      EXPECT_TRUE(std::isnan(cloud.normals[i].x())) << i;
  }
  const std::vector<std::uint8_t> too_short(3, 1);
  options.wanted = too_short;
  EXPECT_THROW(estimate_normals(cloud, options), std::invalid_argument);
}

TEST(Normals, MatchPclOnTheBunny) {
  const std::string path = test::shared_data("pcl/bun0.pcd");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  PointCloud cloud = read_pcd(path);
  const auto reference = test::read_csv(test::test_data("reference/bun0_normals_k10.csv"));
  ASSERT_EQ(reference.size(), cloud.size());
  NormalOptions options;
  options.neighborhood = Neighborhood::Knn(10);
  options.viewpoint = Vec3f::Zero();
  estimate_normals(cloud, options);
  float worst = 0.0f;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    for (int d = 0; d < 3; ++d)
      worst = std::max(worst, std::abs(cloud.normals[i][d] - reference[i][d]));
    worst = std::max(worst, std::abs(cloud.curvature[i] - reference[i][3]));
  }
  EXPECT_LE(worst, 1e-4f);
  RecordProperty("max_abs_diff_vs_pcl", std::to_string(worst));
}

}  // namespace
}  // namespace primlabel
