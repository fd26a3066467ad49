// Touching objects are cut where a fitted can ends and its neighbour starts (shape_split.hpp): a
// can against a box of its height and colour, whose tangent contact the crease cut does not see.
// Objects alone stay whole. Balls in contact, which the crease split cuts apart and the
// occlusion merge would join, stay apart. Organised scans ray-cast from boxes, upright cans,
// balls and rounded boxes on a table (table_scan.hpp).

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "primlabel/tabletop/segmentation_eval.hpp"
#include "primlabel/tabletop/shape_split.hpp"
#include "primlabel/tabletop/tabletop.hpp"
#include "table_scan.hpp"

namespace primlabel::tabletop {
namespace {

using test::Ball;
using test::Box;
using test::Can;
using test::RoundedBox;
using test::scan;

TabletopOptions given_up(bool shapes) {
  TabletopOptions options;
  options.up_source = UpAxisSource::kGiven;
  options.up = Vec3f::UnitZ();
  options.shapes.enabled = shapes;
  return options;
}

// Without the shape split the objects share a cluster; with it each object is one cluster.
void expect_split(const PointCloud& cloud, std::size_t objects) {
  const TabletopResult joined = segment_tabletop(cloud, given_up(false), RunContext{2});
  ASSERT_TRUE(joined.ok()) << joined.message;
  EXPECT_LT(joined.clusters.size(), objects) << "the scene does not test the shape split";
  const TabletopResult split = segment_tabletop(cloud, given_up(true), RunContext{2});
  ASSERT_TRUE(split.ok()) << split.message;
  EXPECT_EQ(split.clusters.size(), objects);
  for (const ObjectScore& o : evaluate_segmentation(cloud, split).objects)
    EXPECT_GT(o.best_iou, 0.9) << "object " << o.object_id;
}

constexpr std::uint32_t kRed = 0xC81E1E;
constexpr std::uint32_t kBlue = 0x1E5AC8;

TEST(TabletopShapeSplit, CanAgainstABoxOfItsHeightAndColourIsSplit) {
  // The can touches the box's right face (0.5 mm apart); both are 12 cm tall and red.
  expect_split(scan({{{-0.15f, 0.10f, 0.0f}, {0.0f, 0.22f, 0.12f}, 20, kRed}},
                    {{0.0405f, 0.16f, 0.04f, 0.0f, 0.12f, 30, kRed}}),
               2);
}

TEST(TabletopShapeSplit, CanAgainstTheFrontOfABoxIsSplit) {
  // The can stands against the box's face turned to the sensor.
  expect_split(scan({{{-0.12f, 0.20f, 0.0f}, {0.08f, 0.30f, 0.10f}, 20, kRed}},
                    {{-0.02f, 0.1595f, 0.04f, 0.0f, 0.10f, 30, kRed}}),
               2);
}

TEST(TabletopShapeSplit, ObjectsAloneStayWhole) {
  // Two boxes and a can, apart: every connection on them is convex or flat.
  const PointCloud cloud = scan({{{-0.30f, 0.10f, 0.0f}, {-0.15f, 0.25f, 0.10f}, 20, kRed},
                                 {{0.15f, 0.30f, 0.0f}, {0.30f, 0.45f, 0.16f}, 40, 0x1E5AC8}},
                                {{0.0f, 0.16f, 0.04f, 0.0f, 0.12f, 30, kRed}});
  for (const bool shapes : {false, true}) {
    const TabletopResult result = segment_tabletop(cloud, given_up(shapes), RunContext{2});
    ASSERT_TRUE(result.ok()) << result.message;
    EXPECT_EQ(result.clusters.size(), 3u) << "shape split " << shapes;
    EXPECT_GT(evaluate_segmentation(cloud, result).mean_object_iou, 0.95);
  }
}

TEST(TabletopShapeSplit, APotKeepsItsHandle) {
  // A pot 16 cm wide with a block of a handle on its side, 4 cm above the table: the handle lies
  // outside the pot's wall but stays closer to it than the pot is wide. (The crease split, which
  // cuts this blocky handle at its sharp fold but not a real handle's, is off.)
  const PointCloud cloud = scan({{{0.075f, 0.17f, 0.04f}, {0.115f, 0.20f, 0.10f}, 20, kRed}},
                                {{0.0f, 0.20f, 0.08f, 0.0f, 0.14f, 20, kRed}});
  TabletopOptions options = given_up(true);
  options.creases.enabled = false;
  const TabletopResult result = segment_tabletop(cloud, options, RunContext{2});
  ASSERT_TRUE(result.ok()) << result.message;
  ASSERT_EQ(result.clusters.size(), 1u);
  EXPECT_GT(evaluate_segmentation(cloud, result).mean_object_iou, 0.95);
}

TEST(TabletopShapeSplit, StackOfOneFootprintIsCutAtItsColourSeam) {
  // A blue box on a red box of the same footprint: one plane fits each side of both, and no
  // strip of the lower top is seen beside the upper box for the stacked split.
  const PointCloud stack = scan({{{-0.06f, 0.15f, 0.0f}, {0.06f, 0.25f, 0.08f}, 20, kRed},
                                 {{-0.06f, 0.15f, 0.08f}, {0.06f, 0.25f, 0.15f}, 30, kBlue}});
  expect_split(stack, 2);
  // Without colour evidence (colour not registered to depth), nothing tells them apart.
  TabletopOptions no_colour = given_up(true);
  no_colour.shapes.use_colour = false;
  const TabletopResult blind = segment_tabletop(stack, no_colour, RunContext{2});
  ASSERT_TRUE(blind.ok()) << blind.message;
  EXPECT_EQ(blind.clusters.size(), 1u);
  // Of one colour, nothing tells them apart.
  const PointCloud one_colour = scan({{{-0.06f, 0.15f, 0.0f}, {0.06f, 0.25f, 0.08f}, 20, kRed},
                                      {{-0.06f, 0.15f, 0.08f}, {0.06f, 0.25f, 0.15f}, 30, kRed}});
  const TabletopResult result = segment_tabletop(one_colour, given_up(true), RunContext{2});
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_EQ(result.clusters.size(), 1u);
}

TEST(TabletopShapeSplit, SurfacesOfTwoEvenColoursInOnePlaneAreCut) {
  // Two boxes of one height side by side, 0.5 mm apart, their fronts and tops in one plane each:
  // no crease between them, one fitted plane across both, a red half and a blue half.
  expect_split(scan({{{-0.12f, 0.15f, 0.0f}, {0.0f, 0.25f, 0.10f}, 20, kRed},
                     {{0.0005f, 0.15f, 0.0f}, {0.12f, 0.25f, 0.10f}, 30, kBlue}}),
               2);
}

// A ball of `radius` touching `ball` (0.5 mm apart) in the horizontal direction (dx, dy).
Ball touching(const Ball& ball, float radius, float dx, float dy, std::uint32_t label) {
  const float apart = ball.radius + radius + 0.0005f, rise = ball.radius - radius;
  const float across = std::sqrt(apart * apart - rise * rise) / std::hypot(dx, dy);
  return {ball.x + across * dx, ball.y + across * dy, radius, label, ball.rgb};
}

TEST(TabletopShapeSplit, BallsInContactAreSplit) {
  // Two red balls of one size touching, partly one behind the other. The crease split cuts them
  // at their contact, but the occlusion merge joins them again (one height and colour, no table
  // seen between them) unless each ball's solid keeps the other apart.
  const Ball ball{-0.05f, 0.20f, 0.045f, 20, kRed};
  expect_split(scan({}, {}, 5, {ball, touching(ball, 0.045f, 0.8f, 0.6f, 30)}), 2);
  const Ball small{0.05f, 0.15f, 0.035f, 20, kRed};
  expect_split(scan({}, {}, 5, {small, touching(small, 0.035f, -1.0f, 1.0f, 30)}), 2);
}

TEST(TabletopShapeSplit, BallsAndRoundedBoxesAloneStayWhole) {
  // A ball alone is one object; so are boxes whose edges are rounded to 2 and 4 cm (strips of
  // cylinders, corners eighths of a ball of an object's size).
  const PointCloud cloud = scan({}, {}, 5, {{-0.22f, 0.10f, 0.045f, 20, kRed}},
                                {{{-0.10f, 0.30f, 0.0f}, {0.04f, 0.40f, 0.12f}, 0.02f, 30, kRed},
                                 {{0.10f, 0.30f, 0.0f}, {0.24f, 0.40f, 0.12f}, 0.04f, 40, kBlue}});
  for (const bool shapes : {false, true}) {
    const TabletopResult result = segment_tabletop(cloud, given_up(shapes), RunContext{2});
    ASSERT_TRUE(result.ok()) << result.message;
    EXPECT_EQ(result.clusters.size(), 3u) << "shape split " << shapes;
    EXPECT_GT(evaluate_segmentation(cloud, result).mean_object_iou, 0.95);
  }
}

TEST(TabletopShapeSplit, SameResultForAnyThreadCount) {
  const PointCloud cloud = scan({{{-0.15f, 0.10f, 0.0f}, {0.0f, 0.22f, 0.12f}, 20, kRed}},
                                {{0.0405f, 0.16f, 0.04f, 0.0f, 0.12f, 30, kRed}});
  const TabletopResult one = segment_tabletop(cloud, given_up(true), RunContext{1});
  const TabletopResult two = segment_tabletop(cloud, given_up(true), RunContext{2});
  ASSERT_TRUE(one.ok()) << one.message;
  EXPECT_EQ(one.clusters, two.clusters);
}

TEST(TabletopShapeSplit, UnorganisedCloudsAreReturnedAsTheyAre) {
  PointCloud cloud = scan({{{-0.15f, 0.10f, 0.0f}, {0.0f, 0.22f, 0.12f}, 20, kRed}});
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  const std::vector<std::vector<std::uint32_t>> clusters = {{0, 1, 2}, {5}};
  EXPECT_EQ(split_by_shape(cloud, {}, Vec3f::UnitZ(), clusters, ShapeSplitOptions{}),
            (std::vector<std::vector<std::uint32_t>>{{0, 1, 2}, {5}}));
}

TEST(TabletopShapeSplit, BadOptionsAreRejected) {
  ShapeSplitOptions options;
  options.noise_sigmas = 0.0f;
  EXPECT_THROW(split_by_shape(PointCloud{}, {}, Vec3f::UnitZ(), {}, options),
               std::invalid_argument);
  options = {};
  options.outside_share = 1.0f;
  EXPECT_THROW(options.validate(), std::invalid_argument);
  options = {};
  options.max_radius = options.min_radius;
  EXPECT_THROW(options.validate(), std::invalid_argument);
  options = {};
  options.seam_explained = 1.0f;
  EXPECT_THROW(options.validate(), std::invalid_argument);
  options = {};
  options.material_separation = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(options.validate(), std::invalid_argument);
  // An organised cloud needs a height for every point.
  PointCloud organised = scan({{{-0.15f, 0.10f, 0.0f}, {0.0f, 0.22f, 0.12f}, 20, kRed}});
  EXPECT_THROW(split_by_shape(organised, {}, Vec3f::UnitZ(), {{0, 1}}, ShapeSplitOptions{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::tabletop
