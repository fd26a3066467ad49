// Cluster refinement of the table-top filter: stacked objects are split at the supporting
// surface; parts of one object cut apart by an occluder are joined, and neighbouring objects are
// not. Synthetic point sets, and organised scans ray-cast from boxes on a table.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "primlabel/tabletop/segmentation_eval.hpp"
#include "primlabel/tabletop/stacked_split.hpp"
#include "primlabel/tabletop/tabletop.hpp"
#include "table_scan.hpp"

namespace primlabel::tabletop {
namespace {

constexpr float kPi = 3.14159265f;
const Eigen::Vector4f kTable(0, 0, 1, 0);  // z = 0, up = +z

// An upright cylinder's wall from z0 to z1 and, optionally, its top disc without the part
// under `hole_radius` (hidden under what stands on it). Spacing about `step`.
void add_cylinder(std::vector<Vec3f>& points, float radius, float z0, float z1, bool top,
                  float hole_radius = 0.0f, float step = 0.003f) {
  const int around = static_cast<int>(2 * kPi * radius / step);
  for (float z = z0; z <= z1; z += step)
    for (int k = 0; k < around; ++k) {
      const float a = 2 * kPi * float(k) / float(around);
      points.emplace_back(radius * std::cos(a), radius * std::sin(a), z);
    }
  if (!top) return;
  for (float x = -radius; x <= radius; x += step)
    for (float y = -radius; y <= radius; y += step) {
      const float r = std::hypot(x, y);
      if (r <= radius && r >= hole_radius) points.emplace_back(x, y, z1);
    }
}

std::vector<float> heights(const std::vector<Vec3f>& points) {
  std::vector<float> h;
  for (const Vec3f& p : points) h.push_back(p.z());
  return h;
}

std::vector<std::uint32_t> all(std::size_t n) {
  std::vector<std::uint32_t> idx(n);
  for (std::size_t i = 0; i < n; ++i) idx[i] = static_cast<std::uint32_t>(i);
  return idx;
}

TEST(TabletopStackedSplit, CanOnATinIsSplitAtTheTinsLid) {
  std::vector<Vec3f> points;
  add_cylinder(points, 0.10f, 0.0f, 0.07f, true, 0.035f);  // tin, lid free around the can
  const std::size_t tin = points.size();
  add_cylinder(points, 0.035f, 0.07f, 0.17f, true);  // can
  const auto clusters =
      split_stacked(points, heights(points), kTable, {all(points.size())}, StackSplitOptions{});
  ASSERT_EQ(clusters.size(), 2u);
  // The tin is the larger part; the can's lowest row (in the lid's band) goes with the can.
  std::size_t tin_in_first = 0, can_in_second = 0;
  for (std::uint32_t i : clusters[0]) tin_in_first += i < tin;
  for (std::uint32_t i : clusters[1]) can_in_second += i >= tin;
  EXPECT_EQ(tin_in_first, tin);
  EXPECT_EQ(can_in_second, points.size() - tin);
}

TEST(TabletopStackedSplit, ThreeStackedObjectsGiveThreeClusters) {
  std::vector<Vec3f> points;
  add_cylinder(points, 0.12f, 0.0f, 0.05f, true, 0.07f);
  add_cylinder(points, 0.07f, 0.05f, 0.10f, true, 0.03f);
  add_cylinder(points, 0.03f, 0.10f, 0.16f, true);
  const auto clusters =
      split_stacked(points, heights(points), kTable, {all(points.size())}, StackSplitOptions{});
  EXPECT_EQ(clusters.size(), 3u);
}

// A box [x0, x1] x [y0, y1] x [z0, z1] as seen from above: its top every `step` except the part
// under [0, hx] x [0, hy] (hidden under what stands on it), its sides three times sparser.
void add_box(std::vector<Vec3f>& points, float x0, float x1, float y0, float y1, float z0, float z1,
             float hx = 0.0f, float hy = 0.0f, float step = 0.003f) {
  const float side = 3 * step;
  for (float z = z0; z < z1; z += side) {
    for (float x = x0; x <= x1; x += side) {
      points.emplace_back(x, y0, z);
      points.emplace_back(x, y1, z);
    }
    for (float y = y0 + side; y < y1; y += side) {
      points.emplace_back(x0, y, z);
      points.emplace_back(x1, y, z);
    }
  }
  for (float x = x0; x <= x1; x += step)
    for (float y = y0; y <= y1; y += step)
      if (!(x < hx && y < hy)) points.emplace_back(x, y, z1);
}

TEST(TabletopStackedSplit, BoxOnABoxOfNearlyTheSameSizeIsSplit) {
  // The upper box covers 72% of the lower one's top, flush with two of its sides: the lower top
  // is seen only as a 3 cm strip, all of it outside the upper footprint.
  std::vector<Vec3f> points;
  add_box(points, 0.0f, 0.2f, 0.0f, 0.2f, 0.0f, 0.1f, 0.17f, 0.17f);
  const std::size_t lower = points.size();
  add_box(points, 0.0f, 0.17f, 0.0f, 0.17f, 0.1f, 0.2f);
  const auto clusters =
      split_stacked(points, heights(points), kTable, {all(points.size())}, StackSplitOptions{});
  ASSERT_EQ(clusters.size(), 2u);
  // The lower box's part (its flush sides' top rows go with the upper box).
  std::size_t in_first = 0;
  for (std::uint32_t i : clusters[0]) in_first += i < lower;
  const auto& lower_part = 2 * in_first > clusters[0].size() ? clusters[0] : clusters[1];
  std::size_t lower_points = 0;
  for (std::uint32_t i : lower_part) lower_points += i < lower;
  EXPECT_GT(double(lower_points), 0.95 * double(lower));
  EXPECT_GT(double(lower_points), 0.95 * double(lower_part.size()));
}

TEST(TabletopStackedSplit, ContainersBoxesAndLowSurfacesStayWhole) {
  StackSplitOptions options;
  // A pot with a raised floor: its walls rise around the floor, not on a part of it.
  std::vector<Vec3f> pot;
  add_cylinder(pot, 0.08f, 0.0f, 0.12f, false);
  for (float x = -0.08f; x <= 0.08f; x += 0.003f)
    for (float y = -0.08f; y <= 0.08f; y += 0.003f)
      if (std::hypot(x, y) < 0.078f) pot.emplace_back(x, y, 0.03f);
  EXPECT_EQ(split_stacked(pot, heights(pot), kTable, {all(pot.size())}, options).size(), 1u);
  // A plain tin: its lid has nothing on it.
  std::vector<Vec3f> tin;
  add_cylinder(tin, 0.1f, 0.0f, 0.07f, true);
  EXPECT_EQ(split_stacked(tin, heights(tin), kTable, {all(tin.size())}, options).size(), 1u);
  // A plinth 1 cm high is below min_support_height: a foot, not a supporting object.
  std::vector<Vec3f> footed;
  add_cylinder(footed, 0.1f, 0.0f, 0.01f, true, 0.035f);
  add_cylinder(footed, 0.035f, 0.01f, 0.15f, true);
  EXPECT_EQ(split_stacked(footed, heights(footed), kTable, {all(footed.size())}, options).size(),
            1u);
  options.enabled = false;
  std::vector<Vec3f> stack;
  add_cylinder(stack, 0.10f, 0.0f, 0.07f, true, 0.035f);
  add_cylinder(stack, 0.035f, 0.07f, 0.17f, true);
  EXPECT_EQ(split_stacked(stack, heights(stack), kTable, {all(stack.size())}, options).size(), 1u);
  options.enabled = true;
  options.peak_factor = 0.5f;
  EXPECT_THROW(split_stacked(stack, heights(stack), kTable, {}, options), std::invalid_argument);
}

using test::Box;
// The refinement tests' scans: boxes only, their own noise seed.
PointCloud scan(const std::vector<Box>& boxes) { return test::scan(boxes, {}, 3); }

TabletopResult segment(const PointCloud& cloud, bool merge = true) {
  TabletopOptions options;
  options.up_source = UpAxisSource::kGiven;
  options.up = Vec3f::UnitZ();
  options.merge.enabled = merge;
  return segment_tabletop(cloud, options, RunContext{2});
}

const Box kTallFront{{-0.04f, 0.0f, 0.0f}, {0.04f, 0.08f, 0.25f}, 20, 0xE6194B};

TEST(TabletopOcclusionMerge, ObjectCutByANearerObjectIsJoined) {
  // A long low box behind a tall narrow one: seen left and right of it, 10+ cm apart.
  const PointCloud cloud =
      scan({kTallFront, {{-0.2f, 0.2f, 0.0f}, {0.2f, 0.3f, 0.06f}, 30, 0x3CB44B}});
  const TabletopResult split = segment(cloud, false);
  ASSERT_TRUE(split.ok()) << split.message;
  EXPECT_EQ(split.clusters.size(), 3u);  // Euclidean clustering alone: two parts of the low box
  const TabletopResult joined = segment(cloud);
  ASSERT_TRUE(joined.ok()) << joined.message;
  ASSERT_EQ(joined.clusters.size(), 2u);
  const SegmentationScores scores = evaluate_segmentation(cloud, joined);
  EXPECT_GT(scores.mean_object_iou, 0.95);
  // Deterministic for any thread count.
  TabletopOptions options;
  options.up_source = UpAxisSource::kGiven;
  options.up = Vec3f::UnitZ();
  EXPECT_EQ(segment_tabletop(cloud, options, RunContext{1}).clusters, joined.clusters);
}

TEST(TabletopOcclusionMerge, ObjectsWithTheTableSeenBetweenThemStaySeparate) {
  // Two equal deep boxes of one colour, 12 cm apart, behind a wider one: the front box hides
  // the near part of the gap (they are linked across it), but the table is seen in its far part.
  const PointCloud cloud = scan({{{-0.1f, 0.0f, 0.0f}, {0.1f, 0.08f, 0.15f}, 20, 0xE6194B},
                                 {{-0.3f, 0.2f, 0.0f}, {-0.06f, 0.6f, 0.06f}, 30, 0x3CB44B},
                                 {{0.06f, 0.2f, 0.0f}, {0.3f, 0.6f, 0.06f}, 40, 0x3CB44B}});
  const TabletopResult result = segment(cloud);
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_EQ(result.clusters.size(), 3u);
  EXPECT_GT(evaluate_segmentation(cloud, result).mean_object_iou, 0.95);
}

TEST(TabletopOcclusionMerge, ObjectsOfDifferentHeightsOrColoursStaySeparate) {
  // A low box right behind the tall one (adjacent in the image, no table seen between them).
  const PointCloud behind =
      scan({kTallFront, {{-0.1f, 0.11f, 0.0f}, {0.1f, 0.2f, 0.1f}, 30, 0x3CB44B}});
  const TabletopResult result = segment(behind);
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_EQ(result.clusters.size(), 2u);
  // Two boxes of one height, one behind the other and adjacent in the image, of two colours.
  const PointCloud two = scan({{{-0.1f, 0.0f, 0.0f}, {0.1f, 0.08f, 0.1f}, 20, 0xE6194B},
                               {{-0.1f, 0.11f, 0.0f}, {0.1f, 0.2f, 0.1f}, 30, 0x3CB44B}});
  EXPECT_EQ(segment(two).clusters.size(), 2u);
}

}  // namespace
}  // namespace primlabel::tabletop
