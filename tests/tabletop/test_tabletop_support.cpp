// The supporting surface: the table is the lowest horizontal surface with things standing on it,
// not the largest one - a tray, a large book or a wide box top can hold more of the image than
// the table seen around them.

#include <gtest/gtest.h>

#include "primlabel/tabletop/segmentation_eval.hpp"
#include "primlabel/tabletop/tabletop.hpp"
#include "table_scan.hpp"

namespace primlabel::tabletop {
namespace {

using test::Box;
using test::Can;

TabletopResult segment(const PointCloud& cloud, bool choose_support = true) {
  TabletopOptions options;
  options.support.enabled = choose_support;
  options.up_source = UpAxisSource::kGiven;
  options.up = Vec3f::UnitZ();
  RunContext context;
  context.threads = 2;
  return segment_tabletop(cloud, options, context);
}

// A wide low box (a tray or a stack of books) covering most of the table in view, a can
// standing on it and a box beside it on the table.
PointCloud tray_scene(float tray_height) {
  return test::scan({{{-0.42f, -0.2f, 0.0f}, {0.42f, 0.95f, tray_height}, 20, 0x4363D8},
                     {{0.53f, 0.0f, 0.0f}, {0.59f, 0.06f, 0.12f}, 40, 0xE6194B}},
                    {{0.0f, 0.4f, 0.04f, tray_height, tray_height + 0.12f, 30, 0x3CB44B}}, 7);
}

TEST(TabletopSupport, TheTableIsTheLowestSurfaceWithThingsOnItNotTheLargest) {
  for (const float tray_height : {0.03f, 0.08f}) {
    SCOPED_TRACE("tray " + std::to_string(tray_height) + " m");
    const PointCloud cloud = tray_scene(tray_height);
    std::size_t table_points = 0, tray_points = 0;
    for (std::uint32_t label : cloud.labels) {
      table_points += label == 1;
      tray_points += label == 20;
    }
    ASSERT_GT(tray_points, table_points);  // the tray is the largest plane in view
    const TabletopResult dominant = segment(cloud, false);
    ASSERT_TRUE(dominant.ok()) << dominant.message;
    EXPECT_NEAR(dominant.plane[3], -tray_height, 0.005f);  // so it is the dominant plane
    const TabletopResult result = segment(cloud);
    ASSERT_TRUE(result.ok()) << result.message;
    EXPECT_NEAR(result.plane[3], 0.0f, 0.005f);  // z = 0, not the tray's top
    const SegmentationScores scores = evaluate_segmentation(cloud, result);
    EXPECT_GT(scores.table_f1, 0.97);
    EXPECT_EQ(scores.objects_found, 3u);
    EXPECT_GT(scores.mean_object_iou, 0.9);
  }
}

TEST(TabletopSupport, AFloorFarBelowTheTableIsNotTheSupport) {
  // The table seen with a wide floor beyond its edge, 0.7 m lower: objects stand on the table.
  // (The floor is a box top far below; the table is a box whose top is the table surface.)
  PointCloud cloud = test::scan({{{-3.0f, 0.7f, -0.75f}, {3.0f, 4.0f, -0.7f}, 50, 0x808080},
                                 {{-0.2f, 0.1f, 0.0f}, {-0.1f, 0.2f, 0.1f}, 20, 0xE6194B}},
                                {{0.1f, 0.3f, 0.04f, 0.0f, 0.12f, 30, 0x3CB44B}}, 7);
  for (std::uint32_t& label : cloud.labels)
    if (label == 50) label = 0;  // the floor is neither table nor object
  const TabletopResult result = segment(cloud);
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_NEAR(result.plane[3], 0.0f, 0.005f);
  EXPECT_EQ(result.clusters.size(), 2u);
}

}  // namespace
}  // namespace primlabel::tabletop
