// Building blocks of the table-top filter on synthetic data: voxel grid, plane fit, convex hull,
// Euclidean clustering, the table-plane grid.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stop_token>

#include "primlabel/tabletop/convex_hull.hpp"
#include "primlabel/tabletop/euclidean_clusters.hpp"
#include "primlabel/tabletop/plane_fit.hpp"
#include "primlabel/tabletop/plane_grid.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::tabletop {
namespace {

std::vector<std::uint32_t> all_indices(std::size_t n) {
  std::vector<std::uint32_t> idx(n);
  for (std::size_t i = 0; i < n; ++i) idx[i] = static_cast<std::uint32_t>(i);
  return idx;
}

// A noisy square patch of the plane through `origin` spanned by unit vectors a, b.
void add_patch(std::vector<Vec3f>& points, const Vec3f& origin, const Vec3f& a, const Vec3f& b,
               float size, float step, float noise, std::mt19937& rng) {
  std::normal_distribution<float> jitter(0.0f, noise);
  const Vec3f n = a.cross(b).normalized();
  for (float s = 0; s < size; s += step)
    for (float t = 0; t < size; t += step)
      points.push_back(origin + s * a + t * b + jitter(rng) * n);
}

void add_blob(std::vector<Vec3f>& points, const Vec3f& center, float radius, int count,
              std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-radius, radius);
  for (int i = 0; i < count; ++i) points.push_back(center + Vec3f(u(rng), u(rng), u(rng)));
}

TEST(TabletopVoxelGrid, CentroidPerVoxelAndMembership) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Vec3f> points = {{0.01f, 0.01f, 0.01f}, {0.03f, 0.03f, 0.03f}, {nan, 0, 0},
                               {0.15f, 0.01f, 0.01f}, {0.17f, 0.05f, 0.01f}, {0.55f, 0, 0}};
  const auto valid = finite_indices(points);
  ASSERT_EQ(valid.size(), 5u);
  const VoxelGrid grid = voxel_downsample(points, valid, 0.1f);
  ASSERT_EQ(grid.centroids.size(), 3u);
  EXPECT_TRUE(grid.centroids[0].isApprox(Vec3f(0.02f, 0.02f, 0.02f), 1e-5f));
  EXPECT_TRUE(grid.centroids[1].isApprox(Vec3f(0.16f, 0.03f, 0.01f), 1e-5f));
  EXPECT_TRUE(grid.centroids[2].isApprox(Vec3f(0.55f, 0.0f, 0.0f), 1e-5f));
  EXPECT_EQ(grid.voxel_of_point[2], kNoVoxel);
  EXPECT_EQ(grid.voxel_of_point[0], grid.voxel_of_point[1]);
  EXPECT_EQ(grid.member_offsets.back(), 5u);
  EXPECT_THROW(voxel_downsample(points, valid, 0.0f), std::invalid_argument);
  EXPECT_TRUE(voxel_downsample(points, {}, 0.1f).centroids.empty());
}

// Far outliers are real (a laser's stray return, a depth camera's garbage pixel): the grid takes
// any extent. A far point is a voxel of its own and the scan's voxels stay as they were.
TEST(TabletopVoxelGrid, AFarPointIsAVoxelOfItsOwnAndTheScanKeepsItsVoxels) {
  std::mt19937 rng(11);
  std::vector<Vec3f> points;
  add_blob(points, Vec3f(0.15f, 0.15f, 0.15f), 0.15f, 3000, rng);
  points.push_back(Vec3f::Zero());  // the scan's lowest corner stays the origin of the cells
  const std::size_t scan = points.size();
  const VoxelGrid near = voxel_downsample(points, all_indices(scan), 0.003f);
  for (const float far : {1e4f, 1e6f, 1e18f, std::numeric_limits<float>::max()}) {
    SCOPED_TRACE(far);
    std::vector<Vec3f> with_far = points;
    with_far.push_back({far, 0.1f, 0.1f});
    with_far.push_back({0.1f, -far, far});
    with_far.push_back({-far, -far, -far});  // below the scan: must not take its precision
    const VoxelGrid grid = voxel_downsample(with_far, all_indices(with_far.size()), 0.003f);
    ASSERT_EQ(grid.centroids.size(), near.centroids.size() + 3);
    std::vector<Vec3f> scan_centroids;
    for (const Vec3f& c : grid.centroids)
      if (c.norm() < 1.0f) scan_centroids.push_back(c);
    EXPECT_EQ(scan_centroids, near.centroids);
    for (std::size_t i = scan; i < with_far.size(); ++i)
      EXPECT_EQ(grid.member_offsets[grid.voxel_of_point[i] + 1] -
                    grid.member_offsets[grid.voxel_of_point[i]],
                1u);
    EXPECT_EQ(grid.centroids[grid.voxel_of_point[scan]], with_far[scan]);
  }
}

TEST(TabletopVoxelGrid, ATinyLeafOrAHugeCubeNeedsNoMoreThanOneVoxelAPoint) {
  std::mt19937 rng(12);
  std::vector<Vec3f> points;
  add_blob(points, Vec3f::Zero(), 5e5f, 100000, rng);  // 100k points in a 1e6 m cube
  points.push_back(points[7]);                         // an exact copy shares its voxel
  std::vector<std::uint32_t> shuffled = all_indices(points.size());
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  for (const float leaf : {1e-30f, 0.003f}) {
    SCOPED_TRACE(leaf);
    const VoxelGrid grid = voxel_downsample(points, all_indices(points.size()), leaf);
    EXPECT_EQ(grid.members.size(), points.size());
    EXPECT_EQ(grid.centroids.size(), points.size() - 1);  // random floats: no two share a cell
    EXPECT_EQ(grid.voxel_of_point[7], grid.voxel_of_point[points.size() - 1]);
    // The order of the input does not matter, on the wide path as on the packed one.
    const VoxelGrid again = voxel_downsample(points, shuffled, leaf);
    EXPECT_EQ(again.centroids, grid.centroids);
    EXPECT_EQ(again.voxel_of_point, grid.voxel_of_point);
  }
}

// The voxel filter and the plane fit take their stop token from the RunContext.
TEST(TabletopVoxelGrid, AStoppedRunContextCancelsTheFilterAndTheFit) {
  std::vector<Vec3f> points;
  for (int i = 0; i < 5000; ++i)
    points.emplace_back(0.001f * float(i % 100), 0.001f * float(i / 100), 0.0f);
  const auto valid = finite_indices(points);
  std::stop_source stopped, never;
  stopped.request_stop();
  EXPECT_THROW(voxel_downsample(points, valid, 0.01f, RunContext{1, stopped.get_token()}),
               Cancelled);
  const VoxelGrid plain = voxel_downsample(points, valid, 0.01f);
  const VoxelGrid kept = voxel_downsample(points, valid, 0.01f, RunContext{1, never.get_token()});
  EXPECT_EQ(kept.members, plain.members);
  EXPECT_EQ(kept.voxel_of_point, plain.voxel_of_point);
  const PlaneFitOptions options;
  EXPECT_THROW(fit_plane(points, valid, options, RunContext{1, stopped.get_token()}), Cancelled);
  EXPECT_EQ(fit_plane(points, valid, options, RunContext{1, never.get_token()}).inliers,
            fit_plane(points, valid, options).inliers);
}

TEST(TabletopPlaneFit, FindsNoisyPlaneAmongOutliers) {
  std::mt19937 rng(7);
  std::vector<Vec3f> points;
  // Plane z = 0.1 x + 0.5 (about 5.7 deg tilt), 1 mm noise, plus 40% uniform outliers.
  const Vec3f a = Vec3f(1, 0, 0.1f).normalized(), b(0, 1, 0);
  add_patch(points, Vec3f(0, 0, 0.5f), a, b, 1.0f, 0.01f, 0.001f, rng);
  const std::size_t plane_points = points.size();
  add_blob(points, Vec3f(0.5f, 0.5f, 1.0f), 0.5f, 7000, rng);
  PlaneFitOptions options;
  options.distance_threshold = 0.005f;
  const PlaneFit fit = fit_plane(points, all_indices(points.size()), options);
  ASSERT_EQ(fit.status, PlaneFitStatus::kOk) << fit.message;
  const Vec3f expected_normal = a.cross(b).normalized();
  EXPECT_GT(std::abs(fit.plane.head<3>().dot(expected_normal)), 0.9999f);
  EXPECT_NEAR(std::abs(signed_distance(fit.plane, Vec3f(0, 0, 0.5f))), 0.0f, 1e-3f);
  std::size_t true_inliers = 0;
  for (std::uint32_t i : fit.inliers) true_inliers += i < plane_points;
  EXPECT_GE(true_inliers, plane_points * 99 / 100);
  EXPECT_LE(fit.inliers.size() - true_inliers, plane_points / 50);  // few outliers in the band
}

TEST(TabletopPlaneFit, PrefersTheLargestPlaneWithinTheAngle) {
  std::mt19937 rng(3);
  std::vector<Vec3f> points;
  add_patch(points, Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 0, 1), 1.5f, 0.01f, 0.001f,
            rng);  // wall
  const std::size_t wall = points.size();
  add_patch(points, Vec3f(0, 0.1f, 0.3f), Vec3f(1, 0, 0), Vec3f(0, 1, 0), 0.8f, 0.01f, 0.001f,
            rng);  // table, smaller than the wall
  PlaneFitOptions options;
  options.axis = Vec3f(0, 0, 1);
  const PlaneFit fit = fit_plane(points, all_indices(points.size()), options);
  ASSERT_EQ(fit.status, PlaneFitStatus::kOk) << fit.message;
  EXPECT_GT(fit.plane.z(), 0.999f);  // oriented along the axis
  EXPECT_NEAR(fit.plane[3], -0.3f, 2e-3f);
  EXPECT_GE(fit.inliers.size(), points.size() - wall);  // the table, and the wall's strip at
  EXPECT_LE(fit.inliers.size(), points.size() - wall + 3 * 150);  // its height
  EXPECT_LT(fit.angle_to_axis_deg, 1.0f);
}

TEST(TabletopPlaneFit, TiltedPlaneBeyondTheLimitIsRejectedClearly) {
  std::mt19937 rng(5);
  std::vector<Vec3f> points;
  const float tilt = 30.0f * float(M_PI) / 180.0f;
  add_patch(points, Vec3f::Zero(), Vec3f(std::cos(tilt), 0, std::sin(tilt)), Vec3f(0, 1, 0), 1.0f,
            0.01f, 0.001f, rng);
  PlaneFitOptions options;
  options.axis = Vec3f(0, 0, 1);
  options.max_angle_deg = 15.0f;
  const PlaneFit fit = fit_plane(points, all_indices(points.size()), options);
  EXPECT_EQ(fit.status, PlaneFitStatus::kNotWithinAngle);
  EXPECT_NEAR(fit.angle_to_axis_deg, 30.0f, 0.5f);
  EXPECT_TRUE(fit.rejected_plane.has_value());
  EXPECT_NE(fit.message.find("30."), std::string::npos) << fit.message;
  EXPECT_TRUE(fit.inliers.empty());
}

TEST(TabletopPlaneFit, TooFewOrNoPlanePointsGiveAStatus) {
  PlaneFitOptions options;
  std::vector<Vec3f> two = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_EQ(fit_plane(two, all_indices(2), options).status, PlaneFitStatus::kTooFewPoints);
  EXPECT_EQ(fit_plane(two, {}, options).status, PlaneFitStatus::kTooFewPoints);
  std::mt19937 rng(1);
  std::vector<Vec3f> cloud;  // a uniform box has no 100-point plane within 1 mm
  add_blob(cloud, Vec3f::Zero(), 1.0f, 3000, rng);
  options.distance_threshold = 0.001f;
  const PlaneFit fit = fit_plane(cloud, all_indices(cloud.size()), options);
  EXPECT_EQ(fit.status, PlaneFitStatus::kNoPlane);
  EXPECT_FALSE(fit.message.empty());
  options.distance_threshold = -1.0f;
  EXPECT_THROW(fit_plane(cloud, all_indices(cloud.size()), options), std::invalid_argument);
}

TEST(TabletopPlaneFit, SameResultForOneAndTwoThreads) {
  std::mt19937 rng(11);
  std::vector<Vec3f> points;
  add_patch(points, Vec3f::Zero(), Vec3f(1, 0, 0), Vec3f(0, 1, 0), 1.0f, 0.005f, 0.002f, rng);
  add_blob(points, Vec3f(0.5f, 0.5f, 0.3f), 0.3f, 20000, rng);
  PlaneFitOptions options;
  options.max_scoring_points = 5000;
  const PlaneFit one = fit_plane(points, all_indices(points.size()), options, RunContext{1});
  const PlaneFit two = fit_plane(points, all_indices(points.size()), options, RunContext{2});
  ASSERT_EQ(one.status, PlaneFitStatus::kOk);
  EXPECT_EQ(one.plane, two.plane);
  EXPECT_EQ(one.inliers, two.inliers);
  EXPECT_EQ(one.iterations, two.iterations);
  options.seed = 99;  // another seed still finds the plane
  const PlaneFit other = fit_plane(points, all_indices(points.size()), options);
  EXPECT_GT(std::abs(other.plane.z()), 0.9999f);
}

TEST(TabletopConvexHull, SquareWithInteriorAndEdgePoints) {
  std::vector<Vec2f> points = {{0, 0},    {1, 0},    {1, 1},       {0, 1}, {0.5f, 0.5f},
                               {0.5f, 0}, {1, 0.3f}, {0.2f, 0.7f}, {0, 0}};
  for (int i = 0; i < 200; ++i) points.emplace_back(0.1f + 0.004f * i, 0.9f - 0.004f * i);
  const std::vector<Vec2f> hull = convex_hull(points);
  ASSERT_EQ(hull.size(), 4u);
  EXPECT_EQ(hull[0], Vec2f(0, 0));
  EXPECT_EQ(hull[1], Vec2f(1, 0));
  EXPECT_EQ(hull[2], Vec2f(1, 1));
  EXPECT_EQ(hull[3], Vec2f(0, 1));
  EXPECT_TRUE(hull_contains(hull, Vec2f(0.5f, 0.5f)));
  EXPECT_TRUE(hull_contains(hull, Vec2f(1.0f, 0.5f)));  // on the boundary
  EXPECT_FALSE(hull_contains(hull, Vec2f(1.05f, 0.5f)));
  EXPECT_TRUE(hull_contains(hull, Vec2f(1.05f, 0.5f), 0.1f));
  EXPECT_FALSE(hull_contains(hull, Vec2f(0.95f, 0.5f), -0.1f));
  EXPECT_FALSE(hull_contains({}, Vec2f(0, 0)));
  EXPECT_EQ(convex_hull({{0, 0}, {1, 1}, {2, 2}}).size(), 2u);  // collinear: a segment
}

// The cached squares answer as hull_contains does, near the boundary and far from it, with a
// margin either way; a point at infinity, NaN or far away is answered by the plain test.
TEST(TabletopConvexHull, MembershipBySquaresAnswersAsTheEdgeTest) {
  std::vector<Vec2f> ring;
  for (int k = 0; k < 40; ++k) {
    const float a = 2.0f * float(M_PI) * float(k) / 40.0f;
    ring.emplace_back(0.3f + 0.8f * std::cos(a), -0.2f + 0.5f * std::sin(a));
  }
  const std::vector<Vec2f> hull = convex_hull(ring);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> x(-0.7f, 1.3f), y(-0.9f, 0.5f);
  for (const float margin : {0.0f, 0.01f, -0.02f}) {
    HullMembership membership(hull, margin, 0.02f);
    std::size_t inside = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec2f p(x(rng), y(rng));
      const bool expected = hull_contains(hull, p, margin);
      ASSERT_EQ(membership.contains(p), expected) << p.transpose() << " margin " << margin;
      inside += expected;
    }
    EXPECT_GT(inside, 5000u);
    EXPECT_LT(inside, 18000u);
    for (const Vec2f& odd : {Vec2f(std::numeric_limits<float>::infinity(), 0.0f),
                             Vec2f(std::nanf(""), 0.0f), Vec2f(3e38f, -3e38f)})
      EXPECT_EQ(membership.contains(odd), hull_contains(hull, odd, margin));
  }
}

TEST(TabletopConvexHull, PlaneBasisIsRightHanded) {
  for (const Vec3f& n : {Vec3f(0, 0, 1), Vec3f(0, -0.8f, -0.6f), Vec3f(1, 0, 0)}) {
    Vec3f u, v;
    plane_basis(n, u, v);
    EXPECT_NEAR(u.dot(n), 0.0f, 1e-6f);
    EXPECT_NEAR(v.dot(n), 0.0f, 1e-6f);
    EXPECT_TRUE(u.cross(v).isApprox(n.normalized(), 1e-5f));
  }
}

TEST(TabletopClusters, SeparatedBlobsAndSizeLimits) {
  std::mt19937 rng(2);
  std::vector<Vec3f> points;
  add_blob(points, Vec3f(0, 0, 0), 0.05f, 2000, rng);    // 0 .. 1999
  add_blob(points, Vec3f(0.5f, 0, 0), 0.05f, 500, rng);  // 2000 .. 2499
  add_blob(points, Vec3f(0, 0.5f, 0), 0.02f, 30, rng);   // 2500 .. 2529
  points.push_back(Vec3f(1, 1, 1));                      // isolated
  ClusterOptions options{0.02f, 1, SIZE_MAX};
  auto clusters = euclidean_clusters(points, all_indices(points.size()), options);
  ASSERT_EQ(clusters.size(), 4u);
  EXPECT_EQ(clusters[0].size(), 2000u);
  EXPECT_EQ(clusters[0].front(), 0u);
  EXPECT_EQ(clusters[1].size(), 500u);
  EXPECT_EQ(clusters[1].front(), 2000u);
  EXPECT_EQ(clusters[2].size(), 30u);
  EXPECT_EQ(clusters[3], std::vector<std::uint32_t>{2530});

  options.min_size = 100;
  options.max_size = 1000;
  clusters = euclidean_clusters(points, all_indices(points.size()), options);
  ASSERT_EQ(clusters.size(), 1u);
  EXPECT_EQ(clusters[0].size(), 500u);
  EXPECT_TRUE(euclidean_clusters(points, {}, options).empty());
  options.min_size = 2000;
  EXPECT_THROW(euclidean_clusters(points, all_indices(points.size()), options),
               std::invalid_argument);
}

TEST(TabletopClusters, ToleranceIsExact) {
  // A chain of points 9.9 mm apart is one cluster at 10 mm and singletons at 9.8 mm.
  std::vector<Vec3f> chain;
  for (int i = 0; i < 50; ++i) chain.emplace_back(0.0099f * i, 0.0005f * (i % 3), 0.0f);
  EXPECT_EQ(euclidean_clusters(chain, all_indices(50), {0.010f, 1, SIZE_MAX}).size(), 1u);
  EXPECT_EQ(euclidean_clusters(chain, all_indices(50), {0.0098f, 1, SIZE_MAX}).size(), 50u);
}

TEST(TabletopPlaneGrid, PartsAreConnectedThroughNeighbouringCells) {
  // Two 20 cm patches of the plane z = 0, 5 mm apart, and a third 3 cm away; cells of 1 cm.
  std::vector<Vec3f> points;
  for (float x = 0; x < 0.2f; x += 0.004f)
    for (float y = 0; y < 0.2f; y += 0.004f) {
      points.emplace_back(x, y, 0.0f);
      points.emplace_back(x + 0.205f, y, 0.001f);
      points.emplace_back(x + 0.44f, y, -0.001f);
    }
  const PlaneGrid grid(points, all_indices(points.size()), Eigen::Vector4f(0, 0, 1, 0), 0.01f);
  const auto parts = grid.connected_parts();
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].size(), 2 * parts[1].size());
  EXPECT_TRUE(std::is_sorted(parts[0].begin(), parts[0].end()));
  EXPECT_EQ(parts[1].front(), 2u);  // the far patch's first point
  EXPECT_THROW(PlaneGrid(points, {}, Eigen::Vector4f(0, 0, 1, 0), 0.0f), std::invalid_argument);
}

TEST(TabletopPlaneGrid, LocalNormalsTellASurfaceFromASlice) {
  std::mt19937 rng(5);
  std::vector<Vec3f> points;
  add_patch(points, Vec3f(0, 0, 0), Vec3f::UnitX(), Vec3f::UnitY(), 0.3f, 0.003f, 0.001f, rng);
  const std::size_t floor_points = points.size();
  // A wall x = 0.5 cut by the band |z| <= 1 cm: a strip whose points face sideways.
  for (float y = 0; y < 0.3f; y += 0.003f)
    for (float z = -0.01f; z <= 0.01f; z += 0.002f) points.emplace_back(0.5f, y, z);
  const PlaneGrid grid(points, all_indices(points.size()), Eigen::Vector4f(0, 0, 1, 0), 0.01f);
  std::vector<std::uint32_t> floor(floor_points), wall;
  for (std::uint32_t i = 0; i < floor_points; ++i) floor[i] = i;
  for (std::uint32_t i = floor_points; i < points.size(); ++i) wall.push_back(i);
  EXPECT_GT(grid.fraction_parallel(floor, 20.0f), 0.99);
  EXPECT_LT(grid.fraction_parallel(wall, 20.0f), 0.01);
  EXPECT_EQ(grid.fraction_parallel({}, 20.0f), 0.0);
}

TEST(TabletopPlaneGrid, HullCandidatesKeepTheHullAndCountInsideSkipsFootprints) {
  std::mt19937 rng(6);
  std::vector<Vec3f> points;
  add_patch(points, Vec3f(0, 0, 0), Vec3f::UnitX(), Vec3f::UnitY(), 0.5f, 0.004f, 0.001f, rng);
  const auto all = all_indices(points.size());
  const PlaneGrid grid(points, all, Eigen::Vector4f(0, 0, 1, 0), 0.01f);
  std::vector<Vec2f> projected;
  for (const Vec3f& p : points) projected.push_back(grid.project(p));
  const std::vector<Vec2f> candidates = grid.hull_candidates(all);
  EXPECT_LT(candidates.size(), points.size() / 5);
  EXPECT_EQ(convex_hull(candidates), convex_hull(projected));

  // A 10 cm square over the patch's middle, in plane coordinates.
  const Vec2f centre = grid.project(Vec3f(0.25f, 0.25f, 0));
  const std::vector<Vec2f> square =
      convex_hull({centre + Vec2f(-0.05f, -0.05f), centre + Vec2f(0.05f, -0.05f),
                   centre + Vec2f(0.05f, 0.05f), centre + Vec2f(-0.05f, 0.05f)});
  const std::size_t inside = grid.count_inside(square, 0.0f);
  EXPECT_NEAR(double(inside), 0.01 / (0.004 * 0.004), 0.15 * 0.01 / (0.004 * 0.004));
  EXPECT_LT(grid.count_inside(square, 0.02f), inside / 2);  // shrunk to 6 x 6 cm
  // Cells under an object standing on the middle are not counted.
  std::vector<std::uint32_t> middle;
  for (std::uint32_t i : all)
    if ((grid.project(points[i]) - centre).cwiseAbs().maxCoeff() < 0.05f) middle.push_back(i);
  EXPECT_EQ(grid.count_inside(square, 0.0f, grid.footprint(points, middle, 1)), 0u);
}

}  // namespace
}  // namespace primlabel::tabletop
