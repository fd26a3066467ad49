// Flat clusters within the range-dependent depth noise of the table are table, not objects; flat
// objects near the sensor and anything standing clear of the noise stay objects.

#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <stdexcept>

#include "primlabel/tabletop/segmentation_eval.hpp"
#include "primlabel/tabletop/table_noise.hpp"
#include "primlabel/tabletop/tabletop.hpp"
#include "table_scan.hpp"

namespace primlabel::tabletop {
namespace {

const Vec3f kSensor(0, 0, 0);
constexpr float kTableBand = 0.006f;

// A square patch of points at range `range` along +y (the table plane is z = 0 in height terms:
// each point's height is given separately), with heights alternating +-`height`.
void add_patch(std::vector<Vec3f>& points, std::vector<float>& heights, float range, float height,
               std::vector<std::uint32_t>& cluster) {
  for (int a = 0; a < 20; ++a)
    for (int b = 0; b < 20; ++b) {
      cluster.push_back(static_cast<std::uint32_t>(points.size()));
      points.emplace_back(0.002f * float(a), range + 0.002f * float(b), 0.0f);
      heights.push_back((a + b) % 2 ? height : -height);
    }
}

TEST(TableNoise, FarFlatPatchBeyondTheFixedBandIsTable) {
  std::vector<Vec3f> points;
  std::vector<float> heights;
  std::vector<std::uint32_t> far_patch, near_patch;
  // At 1.6 m sigma = 7.2 mm: 10 mm is noise. At 0.6 m 10 mm is above the 6 mm band: an object.
  add_patch(points, heights, 1.6f, 0.010f, far_patch);
  add_patch(points, heights, 0.6f, 0.010f, near_patch);
  const TableNoiseSplit split =
      separate_table_noise(points, heights, kSensor, {far_patch, near_patch}, kTableBand, {});
  ASSERT_EQ(split.objects.size(), 1u);
  EXPECT_EQ(split.objects[0], near_patch);
  EXPECT_EQ(split.table_points, far_patch);
}

TEST(TableNoise, ObjectStandingClearOfTheNoiseStays) {
  std::vector<Vec3f> points;
  std::vector<float> heights;
  std::vector<std::uint32_t> box;
  add_patch(points, heights, 1.6f, 0.04f, box);  // a 4 cm high top at 1.6 m (3 sigma 22 mm)
  const TableNoiseSplit split =
      separate_table_noise(points, heights, kSensor, {box}, kTableBand, {});
  ASSERT_EQ(split.objects.size(), 1u);
  EXPECT_TRUE(split.table_points.empty());
}

TEST(TableNoise, DisabledKeepsEveryCluster) {
  std::vector<Vec3f> points;
  std::vector<float> heights;
  std::vector<std::uint32_t> far_patch;
  add_patch(points, heights, 1.6f, 0.010f, far_patch);
  TableNoiseOptions options;
  options.enabled = false;
  const TableNoiseSplit split =
      separate_table_noise(points, heights, kSensor, {far_patch}, kTableBand, options);
  EXPECT_EQ(split.objects.size(), 1u);
  EXPECT_TRUE(split.table_points.empty());
}

TEST(TableNoise, TheTableSeenThroughDepthNoiseIsTableOnBothSidesOfIt) {
  // A box on a table whose depth noise grows with the square of the range (the Kinect's): at the
  // far end the table scatters beyond the fixed band, above and below the plane.
  PointCloud cloud = test::scan({{{-0.1f, 0.2f, 0.0f}, {0.1f, 0.3f, 0.1f}, 20, 0xE6194B}});
  std::mt19937 rng(11);
  std::normal_distribution<float> unit(0.0f, 1.0f);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.labels[i] != 1) continue;
    const Vec3f ray = cloud.xyz[i] - cloud.viewpoint.origin;
    const float range = ray.norm();
    cloud.xyz[i] += ray / range * (unit(rng) * 2.82e-3f * range * range);
  }
  TabletopOptions options;
  options.up_source = UpAxisSource::kGiven;
  options.up = Vec3f::UnitZ();
  RunContext context;
  context.threads = 2;
  const TabletopResult result = segment_tabletop(cloud, options, context);
  ASSERT_TRUE(result.ok()) << result.message;
  const SegmentationScores scores = evaluate_segmentation(cloud, result);
  EXPECT_GT(scores.table_recall, 0.999);
  EXPECT_GT(scores.table_precision, 0.995);
  EXPECT_EQ(result.clusters.size(), 1u);
  EXPECT_GT(scores.mean_object_iou, 0.95);
  // Without the noise rule the fixed band loses the table's far, noisy points.
  options.table_noise.enabled = false;
  const SegmentationScores fixed =
      evaluate_segmentation(cloud, segment_tabletop(cloud, options, context));
  EXPECT_LT(fixed.table_recall, scores.table_recall - 0.003);
}

TEST(TableNoise, BadOptionsAreRefusedByName) {
  TableNoiseOptions options;
  options.min_share_in_band = 0.0f;
  EXPECT_THROW(options.validate(), std::invalid_argument);
  options = {};
  options.noise_sigmas = -1.0f;
  EXPECT_THROW(options.validate(), std::invalid_argument);
  options = {};
  options.depth_noise_per_m2 = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(options.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::tabletop
