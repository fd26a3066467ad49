// The table-top filter on the five real mOSD Kinect scenes, scored against their labels. The
// issue's targets are table F1 >= 0.98 and mean object IoU >= 0.90 on every scene.

#include <gtest/gtest.h>

#include <filesystem>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/tabletop/segmentation_eval.hpp"
#include "primlabel/tabletop/tabletop.hpp"

namespace primlabel::tabletop {
namespace {

std::string mosd(const std::string& name) {
  return std::string(PRIMLABEL_SHARED_DATA) + "/mosd/" + name + ".pcd";
}

SegmentationScores score_scene(const std::string& path) {
  const PointCloud cloud = read_pcd(path);
  TabletopOptions options;
  const TabletopResult result = segment_tabletop(cloud, options, RunContext{2});
  EXPECT_TRUE(result.ok()) << result.message;
  return evaluate_segmentation(cloud, result);
}

class MosdScene : public ::testing::TestWithParam<const char*> {};

TEST_P(MosdScene, TableF1AtLeast098) {
  const std::string path = mosd(GetParam());
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const SegmentationScores scores = score_scene(path);
  RecordProperty("table_f1", std::to_string(scores.table_f1));
  EXPECT_GE(scores.table_f1, 0.98)
      << "precision " << scores.table_precision << " recall " << scores.table_recall;
}

INSTANTIATE_TEST_SUITE_P(Mosd, MosdScene,
                         ::testing::Values("learn0", "learn18", "learn28", "learn36", "learn42"));

class MosdObjects : public ::testing::TestWithParam<const char*> {};

TEST_P(MosdObjects, MeanObjectIouAtLeast090) {
  const std::string path = mosd(GetParam());
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const SegmentationScores scores = score_scene(path);
  std::string per_object;
  for (const ObjectScore& o : scores.objects)
    per_object += " " + std::to_string(o.object_id) + ":" + std::to_string(o.best_iou);
  RecordProperty("mean_object_iou", std::to_string(scores.mean_object_iou));
  EXPECT_GE(scores.mean_object_iou, 0.90)
      << "objects found " << scores.objects_found << " true " << scores.objects_true
      << "; best IoU per object:" << per_object;
}

INSTANTIATE_TEST_SUITE_P(Mosd, MosdObjects,
                         ::testing::Values("learn0", "learn18", "learn28", "learn36", "learn42"));

// Printed boxes and mugs stay whole: these scenes' objects fell into two pieces when the shape
// split cut any fitted surface whose colours formed two groups, without asking each group to be
// of one even colour.
class MosdPrintedObjects : public ::testing::TestWithParam<const char*> {};

TEST_P(MosdPrintedObjects, CountedRight) {
  const std::string path = mosd(GetParam());
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const SegmentationScores scores = score_scene(path);
  EXPECT_EQ(scores.objects_found, scores.objects_true) << "mean IoU " << scores.mean_object_iou;
}

INSTANTIATE_TEST_SUITE_P(Mosd, MosdPrintedObjects,
                         ::testing::Values("learn0", "learn1", "learn2", "learn16", "learn21"));

// Boxes whose rounded edge fits a can: learn18's box is seen on both sides of a nearer box, and
// learn17's edge bends 81 degrees. A can's solid handed to the occlusion merge kept learn18's
// two halves apart until a rounded box edge (a flat face running on tangent from the arc's end
// and leaving the cylinder) stopped counting as a can.
class MosdRoundedBoxEdges : public ::testing::TestWithParam<const char*> {};

TEST_P(MosdRoundedBoxEdges, CountedRight) {
  const std::string path = mosd(GetParam());
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const SegmentationScores scores = score_scene(path);
  EXPECT_EQ(scores.objects_found, scores.objects_true) << "mean IoU " << scores.mean_object_iou;
  EXPECT_GE(scores.mean_object_iou, 0.90);
}

INSTANTIATE_TEST_SUITE_P(Mosd, MosdRoundedBoxEdges, ::testing::Values("learn17", "learn18"));

TEST(MosdDeterminism, SameResultForOneAndTwoThreads) {
  const std::string path = mosd("learn36");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const PointCloud cloud = read_pcd(path);
  TabletopOptions options;
  const TabletopResult one = segment_tabletop(cloud, options, RunContext{1});
  const TabletopResult two = segment_tabletop(cloud, options, RunContext{2});
  ASSERT_TRUE(one.ok()) << one.message;
  EXPECT_EQ(one.plane, two.plane);
  EXPECT_EQ(one.table_inliers, two.table_inliers);
  EXPECT_EQ(one.clusters, two.clusters);
}

TEST(MosdRobustness, PclMugSceneTableIsFound) {
  const std::string path =
      std::string(PRIMLABEL_SHARED_DATA) + "/pcl/table_scene_mug_stereo_textured.pcd";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const PointCloud cloud = read_pcd(path);
  TabletopOptions options;
  const TabletopResult result = segment_tabletop(cloud, options, RunContext{2});
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_GT(result.table_inliers.size(), result.valid_points / 4);
  EXPECT_GE(result.clusters.size(), 1u);  // the mug
}

}  // namespace
}  // namespace primlabel::tabletop
