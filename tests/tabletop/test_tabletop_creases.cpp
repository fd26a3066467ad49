// Touching objects are cut apart at the concave creases where they meet (convexity_split.hpp):
// boxes against boxes, a can against a box. Organised scans ray-cast from
// boxes and upright cylinders on a table, and the real mOSD scenes where Euclidean clustering
// alone joins touching boxes.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/tabletop/convexity_split.hpp"
#include "primlabel/tabletop/segmentation_eval.hpp"
#include "primlabel/tabletop/tabletop.hpp"
#include "table_scan.hpp"

namespace primlabel::tabletop {
namespace {

using test::Box;
using test::Can;
using test::scan;

TabletopOptions given_up(bool creases = true) {
  TabletopOptions options;
  options.up_source = UpAxisSource::kGiven;
  options.up = Vec3f::UnitZ();
  options.creases.enabled = creases;
  return options;
}

// Euclidean clustering joins the touching objects into one cluster; the crease cut separates
// them, each object then matching one cluster closely. (The shape split, which also cuts a can
// from a box, is off in both runs.)
void expect_split(const PointCloud& cloud, std::size_t objects) {
  TabletopOptions clusters_only = given_up(false), creases_only = given_up();
  clusters_only.shapes.enabled = creases_only.shapes.enabled = false;
  const TabletopResult joined = segment_tabletop(cloud, clusters_only, RunContext{2});
  ASSERT_TRUE(joined.ok()) << joined.message;
  EXPECT_LT(joined.clusters.size(), objects) << "the scene does not test a crease";
  const TabletopResult split = segment_tabletop(cloud, creases_only, RunContext{2});
  ASSERT_TRUE(split.ok()) << split.message;
  EXPECT_EQ(split.clusters.size(), objects);
  const SegmentationScores scores = evaluate_segmentation(cloud, split);
  for (const ObjectScore& o : scores.objects)
    EXPECT_GT(o.best_iou, 0.9) << "object " << o.object_id;
}

TEST(TabletopCreaseSplit, TwoTouchingBoxesAreSplit) {
  // A low box against a taller, larger one of the same colour (too large to be standing on the
  // low one's top, so the stacked-object split does not apply).
  // The taller box is on the far side from the sensor, so its face above the crease is seen.
  expect_split(scan({{{0.03f, 0.1f, 0.0f}, {0.15f, 0.2f, 0.08f}, 20, 0xE6194B},
                     {{0.15f, 0.0f, 0.0f}, {0.35f, 0.3f, 0.14f}, 30, 0xE6194B}}),
               2);
}

TEST(TabletopCreaseSplit, CanBesideABoxIsSplit) {
  expect_split(scan({{{-0.15f, 0.1f, 0.0f}, {0.0f, 0.25f, 0.1f}, 20, 0x3CB44B}},
                    {{0.035f, 0.16f, 0.035f, 0.0f, 0.12f, 30, 0x3CB44B}}),
               2);
}

TEST(TabletopCreaseSplit, ConvexObjectsStayWhole) {
  // A box and a can alone: every connection on them is convex or flat.
  const PointCloud cloud = scan({{{-0.25f, 0.1f, 0.0f}, {-0.1f, 0.25f, 0.1f}, 20, 0x3CB44B}},
                                {{0.1f, 0.16f, 0.04f, 0.0f, 0.12f, 30, 0xE6194B}});
  const TabletopResult result = segment_tabletop(cloud, given_up(), RunContext{2});
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_EQ(result.clusters.size(), 2u);
  EXPECT_GT(evaluate_segmentation(cloud, result).mean_object_iou, 0.95);
}

TEST(TabletopCreaseSplit, SameResultForAnyThreadCount) {
  const PointCloud cloud = scan({{{-0.15f, 0.1f, 0.0f}, {0.0f, 0.2f, 0.08f}, 20, 0xE6194B},
                                 {{0.0f, 0.05f, 0.0f}, {0.12f, 0.25f, 0.14f}, 30, 0xE6194B}},
                                {{0.18f, 0.15f, 0.04f, 0.0f, 0.12f, 40, 0xE6194B}});
  const TabletopResult one = segment_tabletop(cloud, given_up(), RunContext{1});
  const TabletopResult two = segment_tabletop(cloud, given_up(), RunContext{2});
  ASSERT_TRUE(one.ok()) << one.message;
  EXPECT_EQ(one.clusters, two.clusters);
}

TEST(TabletopCreaseSplit, BadOptionsAreRejected) {
  ConvexitySplitOptions options;
  options.patch_size = 0.0f;
  EXPECT_THROW(split_at_concave_creases(PointCloud{}, {}, options), std::invalid_argument);
  options = {};
  options.concavity_tolerance_deg = 90.0f;
  EXPECT_THROW(options.validate(), std::invalid_argument);
}

// Real Kinect scenes where touching boxes used to come out as one cluster.
class MosdCreases : public ::testing::TestWithParam<const char*> {};

TEST_P(MosdCreases, ObjectCountRightAndMeanIouAtLeast090) {
  const std::string path = std::string(PRIMLABEL_SHARED_DATA) + "/mosd/" + GetParam() + ".pcd";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const PointCloud cloud = read_pcd(path);
  const TabletopResult result = segment_tabletop(cloud, TabletopOptions{}, RunContext{2});
  ASSERT_TRUE(result.ok()) << result.message;
  const SegmentationScores scores = evaluate_segmentation(cloud, result);
  EXPECT_EQ(scores.objects_found, scores.objects_true);
  EXPECT_GE(scores.mean_object_iou, 0.90);
}

INSTANTIATE_TEST_SUITE_P(Mosd, MosdCreases, ::testing::Values("learn19", "learn21"));

}  // namespace
}  // namespace primlabel::tabletop
