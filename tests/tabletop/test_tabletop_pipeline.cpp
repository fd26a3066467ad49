// The whole table-top filter on a synthetic scene, the bad-input results and determinism.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stop_token>

#include "primlabel/tabletop/segmentation_eval.hpp"
#include "primlabel/tabletop/tabletop.hpp"

namespace primlabel::tabletop {
namespace {

// A 1.2 x 0.8 m table at z = 0.7 above a floor strip (z = 0) and beside a wall, with two boxes on
// it and one floating above the edge; ground truth in mOSD labels (1 table, 20/30 objects).
PointCloud synthetic_scene(float noise = 0.001f) {
  std::mt19937 rng(4);
  std::normal_distribution<float> jitter(0.0f, noise);
  PointCloud cloud;
  const auto add = [&](const Vec3f& p, std::uint32_t label) {
    cloud.xyz.push_back(p + Vec3f(jitter(rng), jitter(rng), jitter(rng)));
    cloud.labels.push_back(label);
  };
  const float step = 0.006f;
  for (float x = 0; x < 1.2f; x += step)
    for (float y = 0; y < 0.8f; y += step) {
      const bool under_box = (x > 0.2f && x < 0.4f && y > 0.2f && y < 0.35f) ||
                             (x > 0.7f && x < 0.8f && y > 0.5f && y < 0.6f);
      if (!under_box) add(Vec3f(x, y, 0.7f), 1);
    }
  for (float x = -0.5f; x < 1.7f; x += 2 * step)  // floor strip in front, lower than the table
    for (float y = -0.6f; y < -0.1f; y += 2 * step) add(Vec3f(x, y, 0.0f), 0);
  for (float x = -0.5f; x < 1.7f; x += 2 * step)  // wall behind
    for (float z = 0.0f; z < 0.8f; z += 2 * step) add(Vec3f(x, 1.0f, z), 0);
  const auto box = [&](Vec3f lo, Vec3f hi, std::uint32_t label) {
    for (float x = lo.x(); x <= hi.x(); x += step)
      for (float y = lo.y(); y <= hi.y(); y += step) add(Vec3f(x, y, hi.z()), label);  // top
    for (float x = lo.x(); x <= hi.x(); x += step)
      for (float z = lo.z(); z <= hi.z(); z += step) {
        add(Vec3f(x, lo.y(), z), label);
        add(Vec3f(x, hi.y(), z), label);
      }
    for (float y = lo.y(); y <= hi.y(); y += step)
      for (float z = lo.z(); z <= hi.z(); z += step) {
        add(Vec3f(lo.x(), y, z), label);
        add(Vec3f(hi.x(), y, z), label);
      }
  };
  box(Vec3f(0.2f, 0.2f, 0.7f), Vec3f(0.4f, 0.35f, 0.82f), 20);
  box(Vec3f(0.7f, 0.5f, 0.7f), Vec3f(0.8f, 0.6f, 0.9f), 30);
  box(Vec3f(1.4f, 0.3f, 0.75f), Vec3f(1.5f, 0.4f, 0.85f), 0);  // outside the table's hull
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.viewpoint.origin = Vec3f(0.6f, -1.0f, 1.5f);
  return cloud;
}

TabletopOptions given_up_options() {
  TabletopOptions options;
  options.up_source = UpAxisSource::kGiven;
  options.up = Vec3f(0, 0, 1);
  return options;
}

TEST(TabletopPipeline, SegmentsTableAndObjectsOfASyntheticScene) {
  const PointCloud cloud = synthetic_scene();
  const TabletopResult result = segment_tabletop(cloud, given_up_options());
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_NEAR(result.plane[3], -0.7f, 2e-3f);
  EXPECT_GT(result.plane.z(), 0.9999f);
  EXPECT_GE(result.hull.size(), 4u);
  for (const Vec3f& corner : result.hull) EXPECT_NEAR(corner.z(), 0.7f, 2e-3f);
  ASSERT_EQ(result.clusters.size(), 2u);

  const SegmentationScores scores = evaluate_segmentation(cloud, result);
  EXPECT_GT(scores.table_precision, 0.98);  // the boxes' lowest rows are in the table band
  EXPECT_GT(scores.table_recall, 0.99);
  EXPECT_EQ(scores.objects_true, 2u);
  EXPECT_EQ(scores.objects_found, 2u);
  EXPECT_GT(scores.mean_object_iou, 0.95);

  const auto mask = tabletop_mask(result, cloud.size());
  std::size_t selected = 0;
  for (auto m : mask) selected += m;
  std::size_t objects = 0;
  for (const auto& c : result.clusters) objects += c.size();
  EXPECT_EQ(selected, result.table_inliers.size() + objects);
}

TEST(TabletopPipeline, EstimatedUpFindsTheTableFromATiltedSensor) {
  PointCloud cloud = synthetic_scene();
  // Express the scene in a camera frame looking down at the table (y down, z forward), 40 deg
  // tilt, and give no pose: the sensor's up is -y, 40 deg off the table normal.
  const Eigen::Matrix3f to_camera =
      Eigen::AngleAxisf(-(float(M_PI) / 2 + 40.0f * float(M_PI) / 180.0f), Vec3f::UnitX())
          .toRotationMatrix()
          .transpose();
  const Vec3f eye = cloud.viewpoint.origin;
  for (Vec3f& p : cloud.xyz) p = to_camera * (p - eye);
  cloud.viewpoint = Viewpoint{};
  TabletopOptions options;
  const TabletopResult result = segment_tabletop(cloud, options, RunContext{2});
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_TRUE(result.up.isApprox(to_camera * Vec3f::UnitZ(), 1e-3f)) << result.up.transpose();
  EXPECT_NEAR(result.tilt_deg, 40.0f, 1.0f);
  const SegmentationScores scores = evaluate_segmentation(cloud, result);
  EXPECT_GT(scores.table_f1, 0.99);
  EXPECT_GT(scores.mean_object_iou, 0.95);
}

// The sensor's pose turns its up (-y of the camera) into +z.
Viewpoint upright_sensor(const Vec3f& origin) {
  Viewpoint viewpoint;
  viewpoint.origin = origin;
  viewpoint.orientation = Eigen::AngleAxisf(-float(M_PI) / 2, Vec3f::UnitX());
  return viewpoint;
}

TEST(TabletopPipeline, SensorPoseGivesTheUpAxis) {
  PointCloud cloud = synthetic_scene();
  cloud.viewpoint = upright_sensor(cloud.viewpoint.origin);
  TabletopOptions options;
  options.up_source = UpAxisSource::kSensor;
  const TabletopResult result = segment_tabletop(cloud, options, RunContext{2});
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_GT(result.up.z(), 0.9999f);
  const SegmentationScores scores = evaluate_segmentation(cloud, result);
  EXPECT_GT(scores.table_f1, 0.99);
  EXPECT_GT(scores.mean_object_iou, 0.95);
}

TEST(TabletopPipeline, APlaneSlicingThroughWallsIsNotATable) {
  // A room's four walls and nothing horizontal: within 15 deg of the sensor's up, the best plane
  // is a horizontal slice through the walls - a wide ring of points, dense and two-dimensional
  // in extent, but every one of them on a wall.
  PointCloud room;
  for (float s = 0; s < 2.0f; s += 0.01f)
    for (float z = 0; z < 1.0f; z += 0.01f) {
      room.xyz.emplace_back(s, 0.0f, z);
      room.xyz.emplace_back(s, 2.0f, z);
      room.xyz.emplace_back(0.0f, s, z);
      room.xyz.emplace_back(2.0f, s, z);
    }
  room.width = static_cast<std::uint32_t>(room.size());
  room.viewpoint = upright_sensor(Vec3f(1.0f, 1.0f, 1.5f));
  TabletopOptions options;
  options.up_source = UpAxisSource::kSensor;
  const TabletopResult result = segment_tabletop(room, options, RunContext{2});
  EXPECT_EQ(result.status, TabletopStatus::kPlaneNotHorizontal) << result.message;
  EXPECT_NE(result.message.find("slice"), std::string::npos) << result.message;
  EXPECT_NEAR(result.tilt_deg, 90.0f, 1.0f);  // the dominant plane: a wall
  EXPECT_TRUE(result.table_inliers.empty());
  options.min_table_parallel = 0.0f;  // without the check the slice passes for a table
  EXPECT_TRUE(segment_tabletop(room, options).ok());
}

TEST(TabletopPipeline, VoxelGridGivesTheSameSegmentation) {
  const PointCloud cloud = synthetic_scene();
  TabletopOptions options = given_up_options();
  options.voxel_leaf = 0.01f;
  const TabletopResult result = segment_tabletop(cloud, options);
  ASSERT_TRUE(result.ok()) << result.message;
  const SegmentationScores scores = evaluate_segmentation(cloud, result);
  EXPECT_GT(scores.table_f1, 0.99);
  EXPECT_EQ(scores.objects_found, 2u);
  EXPECT_GT(scores.mean_object_iou, 0.95);
}

TEST(TabletopPipeline, SameResultForOneAndTwoThreads) {
  const PointCloud cloud = synthetic_scene(0.003f);
  TabletopOptions options = given_up_options();
  const TabletopResult one = segment_tabletop(cloud, options, RunContext{1});
  const TabletopResult two = segment_tabletop(cloud, options, RunContext{2});
  ASSERT_TRUE(one.ok());
  EXPECT_EQ(one.plane, two.plane);
  EXPECT_EQ(one.table_inliers, two.table_inliers);
  EXPECT_EQ(one.hull, two.hull);
  EXPECT_EQ(one.clusters, two.clusters);
}

// The stage takes its stop token from the RunContext: stopped, it throws Cancelled (with and
// without the voxel filter); never stopped, it segments exactly as without a token.
TEST(TabletopPipeline, HonoursTheRunContextStop) {
  const PointCloud cloud = synthetic_scene();
  std::stop_source stopped, never;
  stopped.request_stop();
  for (const float leaf : {0.0f, 0.01f}) {
    TabletopOptions options = given_up_options();
    options.voxel_leaf = leaf;
    EXPECT_THROW(segment_tabletop(cloud, options, RunContext{2, stopped.get_token()}), Cancelled)
        << "leaf " << leaf;
    const TabletopResult plain = segment_tabletop(cloud, options, RunContext{2});
    const TabletopResult kept = segment_tabletop(cloud, options, RunContext{2, never.get_token()});
    ASSERT_TRUE(plain.ok()) << plain.message;
    EXPECT_EQ(kept.table_inliers, plain.table_inliers);
    EXPECT_EQ(kept.clusters, plain.clusters);
  }
}

TEST(TabletopPipeline, EmptyAndAllNanCloudsGiveNoValidPoints) {
  PointCloud empty;
  TabletopResult result = segment_tabletop(empty, TabletopOptions{});
  EXPECT_EQ(result.status, TabletopStatus::kNoValidPoints);
  EXPECT_FALSE(result.message.empty());

  PointCloud nan_cloud;
  nan_cloud.xyz.assign(640 * 480, Vec3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  nan_cloud.width = 640;
  nan_cloud.height = 480;
  result = segment_tabletop(nan_cloud, TabletopOptions{});
  EXPECT_EQ(result.status, TabletopStatus::kNoValidPoints);
  EXPECT_TRUE(result.table_inliers.empty());
  EXPECT_TRUE(result.clusters.empty());
  EXPECT_EQ(segment_ids(result, nan_cloud.size()), std::vector<std::int32_t>(nan_cloud.size(), -1));
}

TEST(TabletopPipeline, NoPlaneAndTiltedPlaneGiveAStatus) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  PointCloud scatter;
  for (int i = 0; i < 5000; ++i) scatter.xyz.emplace_back(u(rng), u(rng), u(rng));
  TabletopOptions options = given_up_options();
  options.plane.distance_threshold = 0.002f;
  EXPECT_EQ(segment_tabletop(scatter, options).status, TabletopStatus::kNoPlane);

  PointCloud wall;  // a vertical plane only
  for (float x = 0; x < 1; x += 0.01f)
    for (float z = 0; z < 1; z += 0.01f) wall.xyz.emplace_back(x, 0.0f, z);
  const TabletopResult result = segment_tabletop(wall, given_up_options());
  EXPECT_EQ(result.status, TabletopStatus::kPlaneNotHorizontal);
  EXPECT_NEAR(result.tilt_deg, 90.0f, 0.5f);
}

TEST(TabletopPipeline, InvalidOptionsThrow) {
  const PointCloud cloud = synthetic_scene();
  TabletopOptions options = given_up_options();
  options.up = Vec3f::Zero();
  EXPECT_THROW(segment_tabletop(cloud, options), std::invalid_argument);
  options = given_up_options();
  options.clusters.tolerance = 0.0f;
  EXPECT_THROW(segment_tabletop(cloud, options), std::invalid_argument);
  options = given_up_options();
  options.min_object_height = 1.0f;
  EXPECT_THROW(segment_tabletop(cloud, options), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::tabletop
