// The organised-frame pieces `primlabel-bench organised` measures: the image-plane grid must
// return exactly the radius search's sets (real and synthetic frames, any viewpoint, extreme
// inputs, any thread), and the integral-image normals must be a plane's normal on a plane.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <thread>
#include <vector>

#include "image_grid.hpp"
#include "integral_normals.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::bench {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A pinhole frame (focal f, centre at the image's middle) of a tilted table (z = 1.2 - 0.5 y)
// and a ball of radius 0.1 at (0.05, 0.05, 0.9); every 7th pixel a miss (NaN).
PointCloud synthetic_frame(std::uint32_t width, std::uint32_t height, float focal) {
  PointCloud frame;
  frame.xyz.resize(std::size_t(width) * height);
  frame.width = width;
  frame.height = height;
  const Vec3f centre(0.05f, 0.05f, 0.9f);
  for (std::uint32_t v = 0; v < height; ++v)
    for (std::uint32_t u = 0; u < width; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      const Vec3f ray((float(u) - 0.5f * float(width)) / focal,
                      (float(v) - 0.5f * float(height)) / focal, 1.0f);
      float depth = 1.2f / (1.0f + 0.5f * ray.y());  // the table: z = 1.2 - 0.5 y
      // The ball: the nearest root of |t ray - centre|^2 = r^2.
      const float a = ray.squaredNorm(), b = ray.dot(centre), c = centre.squaredNorm() - 0.01f;
      const float disc = b * b - a * c;
      if (disc >= 0.0f) depth = std::min(depth, (b - std::sqrt(disc)) / a);
      frame.xyz[i] = i % 7 == 3 ? Vec3f::Constant(kNaN) : Vec3f(ray * depth);
    }
  return frame;
}

std::vector<Vec3f> voxel_centroids(const PointCloud& frame, float leaf) {
  return tabletop::voxel_downsample(frame.xyz, tabletop::finite_indices(frame.xyz), leaf).centroids;
}

std::vector<std::uint32_t> sorted(std::vector<std::uint32_t> v) {
  std::sort(v.begin(), v.end());
  return v;
}

// Every point's image-grid set equals the radius search's (capped at 1024, as the labeling
// path searches; no list here reaches the cap), but for the queries the grid declines (their
// sphere, widened by the coordinates' rounding, reaches the image plane): how many it declined.
std::size_t expect_same_sets(const std::vector<Vec3f>& points, const Viewpoint& viewpoint,
                             float radius) {
  const NeighborSearch search(points);
  const auto grid = ImageGrid::build(points, radius, viewpoint);
  EXPECT_NE(grid, nullptr);
  if (!grid) return 0;
  NeighborList expected, found;
  std::size_t checked = 0, declined = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    search.find(points[i], Neighborhood::Hybrid(radius, 1024), expected, /*sorted=*/false);
    found.clear();
    if (!grid->find(points[i], radius, found)) {
      EXPECT_EQ(found.size(), 0u);
      ++declined;
      continue;
    }
    EXPECT_EQ(sorted(found.indices), sorted(expected.indices)) << "point " << i;
    // The same squared distances, bit for bit (the same float arithmetic).
    for (std::size_t k = 0; k < found.size(); ++k) {
      const auto at = std::find(expected.indices.begin(), expected.indices.end(), found.indices[k]);
      if (at == expected.indices.end()) break;  // reported above
      EXPECT_EQ(found.sq_dists[k], expected.sq_dists[std::size_t(at - expected.indices.begin())]);
    }
    ++checked;
  }
  EXPECT_EQ(checked + declined, points.size());
  return declined;
}

TEST(ImageGrid, SameSetsAsTheRadiusSearchOnRealFrames) {
  for (const char* name : {"learn20", "learn33"}) {
    const std::string path = std::string(PRIMLABEL_SHARED_DATA) + "/mosd/" + name + ".pcd";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
    const PointCloud frame = read_cloud(path);
    const std::vector<Vec3f> voxels = voxel_centroids(frame, 0.007f);
    ASSERT_GT(voxels.size(), 10000u);
    for (const float radius : {0.015f, 0.03f, 0.04f}) {
      SCOPED_TRACE(std::string(name) + " r = " + std::to_string(radius));
      EXPECT_EQ(expect_same_sets(voxels, frame.viewpoint, radius), 0u);
    }
  }
}

TEST(ImageGrid, SameSetsOnASyntheticFrameWithMissesAndFullResolution) {
  const PointCloud frame = synthetic_frame(160, 120, 130.0f);
  EXPECT_EQ(expect_same_sets(voxel_centroids(frame, 0.01f), frame.viewpoint, 0.03f), 0u);
  // Every pixel, the misses (NaN) included: they are never neighbours and have none.
  EXPECT_EQ(expect_same_sets(frame.xyz, frame.viewpoint, 0.02f), 0u);
  const auto grid = ImageGrid::build(frame.xyz, 0.02f, frame.viewpoint);
  NeighborList found;
  EXPECT_TRUE(grid->find(Vec3f::Constant(kNaN), 0.02f, found));
  EXPECT_EQ(found.size(), 0u);
}

TEST(ImageGrid, AnyViewpointPose) {
  // The same frame moved to a sensor pose: the projection is taken in the sensor's frame.
  PointCloud frame = synthetic_frame(120, 90, 100.0f);
  const Eigen::Quaternionf rotation(Eigen::AngleAxisf(0.7f, Vec3f(0.3f, -1.0f, 0.4f).normalized()));
  const Vec3f origin(0.4f, -1.5f, 2.0f);
  for (Vec3f& p : frame.xyz)
    if (is_finite(p)) p = rotation * p + origin;
  frame.viewpoint.origin = origin;
  frame.viewpoint.orientation = rotation;
  EXPECT_EQ(expect_same_sets(voxel_centroids(frame, 0.01f), frame.viewpoint, 0.03f), 0u);
}

TEST(ImageGrid, ExtremeInputs) {
  const Viewpoint at_origin;
  // No finite point, a point behind or on the image plane: no grid (the caller searches so).
  EXPECT_EQ(ImageGrid::build(std::vector<Vec3f>(50, Vec3f::Constant(kNaN)), 0.03f, at_origin),
            nullptr);
  EXPECT_EQ(ImageGrid::build({Vec3f(0, 0, 1), Vec3f(0, 0, -1)}, 0.03f, at_origin), nullptr);
  EXPECT_EQ(ImageGrid::build({Vec3f(0, 0, 1), Vec3f(1, 0, 0)}, 0.03f, at_origin), nullptr);
  EXPECT_EQ(ImageGrid::build({Vec3f(0, 0, 1)}, 0.0f, at_origin), nullptr);

  // Far outliers at 1e6 m (on the axis and off it, stretching the image) and coincident points.
  const PointCloud frame = synthetic_frame(80, 60, 70.0f);
  std::vector<Vec3f> points = voxel_centroids(frame, 0.01f);
  points.push_back(Vec3f(0.0f, 0.0f, 1e6f));
  points.push_back(Vec3f(1e6f, -1e6f, 1.0f));
  for (int copy = 0; copy < 5; ++copy) points.push_back(points[10]);
  // The off-axis one is declined: at 1e6 m a float's rounding (6 cm) exceeds its depth (1 m).
  EXPECT_EQ(expect_same_sets(points, at_origin, 0.03f), 1u);

  // A sphere reaching the image plane has no bounded window: the grid declines the query.
  const auto grid = ImageGrid::build(points, 0.03f, at_origin);
  NeighborList found;
  EXPECT_FALSE(grid->find(Vec3f(0.0f, 0.0f, 0.02f), 0.03f, found));
  EXPECT_EQ(found.size(), 0u);
}

TEST(ImageGrid, ThreadsGetTheSameLists) {
  const PointCloud frame = synthetic_frame(160, 120, 130.0f);
  const std::vector<Vec3f> points = voxel_centroids(frame, 0.01f);
  const auto grid = ImageGrid::build(points, 0.03f, frame.viewpoint);
  const auto lists_of = [&](std::size_t first, std::size_t step) {
    std::vector<std::vector<std::uint32_t>> lists(points.size());
    NeighborList found;
    for (std::size_t i = first; i < points.size(); i += step) {
      found.clear();
      grid->find(points[i], 0.03f, found);
      lists[i] = found.indices;
    }
    return lists;
  };
  const auto one = lists_of(0, 1);
  std::vector<std::vector<std::uint32_t>> even, odd;
  std::thread a([&] { even = lists_of(0, 2); }), b([&] { odd = lists_of(1, 2); });
  a.join();
  b.join();
  for (std::size_t i = 0; i < points.size(); ++i)
    EXPECT_EQ(i % 2 == 0 ? even[i] : odd[i], one[i]) << "point " << i;  // same order too
}

TEST(IntegralNormals, APlaneGivesItsNormalFacingTheSensor) {
  // The table alone: z = 1.2 - 0.5 y, so its normal is (0, 0.5, 1) normalised, toward -z.
  PointCloud frame = synthetic_frame(160, 120, 130.0f);
  const IntegralMoments moments(frame);
  Vec3f normal;
  float variation = 1.0f;
  ASSERT_TRUE(moments.normal(10, 100, 30, 115, Vec3f::Zero(), normal, variation));
  const Vec3f expected = -Vec3f(0.0f, 0.5f, 1.0f).normalized();
  EXPECT_GT(normal.dot(expected), 0.99999f);
  EXPECT_LT(variation, 1e-6f);
  EXPECT_NEAR(estimate_focal(frame), 130.0f, 0.01f);

  // Windows clipped to the image, and windows with too few points.
  EXPECT_TRUE(moments.normal(-50, 90, 5, 200, Vec3f::Zero(), normal, variation));
  EXPECT_FALSE(moments.normal(200, 200, 300, 300, Vec3f::Zero(), normal, variation));
  PointCloud empty = frame;
  std::fill(empty.xyz.begin(), empty.xyz.end(), Vec3f::Constant(kNaN));
  const IntegralMoments none(empty);
  EXPECT_FALSE(none.normal(0, 0, 159, 119, Vec3f::Zero(), normal, variation));
  EXPECT_TRUE(std::isnan(estimate_focal(empty)));

  PointCloud unorganised = frame;
  unorganised.height = 1;
  unorganised.width = std::uint32_t(frame.size());
  EXPECT_THROW(IntegralMoments{unorganised}, std::invalid_argument);
}

TEST(IntegralNormals, VoxelsTakeTheirPixelsWindow) {
  const PointCloud frame = synthetic_frame(160, 120, 130.0f);
  const tabletop::VoxelGrid voxels =
      tabletop::voxel_downsample(frame.xyz, tabletop::finite_indices(frame.xyz), 0.02f);
  const std::vector<std::uint32_t> pixels = voxel_pixels(frame, voxels);
  const IntegralMoments moments(frame);
  const VoxelNormals normals =
      integral_voxel_normals(frame, moments, voxels, pixels, 0.03f, estimate_focal(frame));
  ASSERT_EQ(normals.normals.size(), voxels.centroids.size());
  // A voxel's pixel lies near its centroid's projection, and where the window holds no pixel of
  // the ball (about 16 px around (87, 67); a window is ~3 px) the table's normal is found.
  const Vec3f table = -Vec3f(0.0f, 0.5f, 1.0f).normalized();
  std::size_t on_table = 0;
  for (std::size_t v = 0; v < voxels.centroids.size(); ++v) {
    const Vec3f& c = voxels.centroids[v];
    const float u = 130.0f * c.x() / c.z() + 80.0f, row = 130.0f * c.y() / c.z() + 60.0f;
    EXPECT_NEAR(float(pixels[v] % 160), u, 3.0f);
    EXPECT_NEAR(float(pixels[v] / 160), row, 3.0f);
    if (std::hypot(u - 87.2f, row - 67.2f) > 24.0f && is_finite(normals.normals[v])) {
      EXPECT_GT(normals.normals[v].dot(table), 0.999f) << "voxel " << v;
      ++on_table;
    }
  }
  EXPECT_GT(on_table, 50u);
}

}  // namespace
}  // namespace primlabel::bench
