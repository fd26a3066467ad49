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

namespace primlabel::tabletop {
namespace {

struct Box {
  Vec3f lo, hi;
  std::uint32_t label, rgb;
};

struct Can {  // upright cylinder standing on z = base
  float x, y, radius, base, top;
  std::uint32_t label, rgb;
};

// Ray parameter of the nearest hit of an upright closed cylinder, or infinity.
float hit_can(const Can& can, const Vec3f& eye, const Vec3f& ray) {
  float nearest = std::numeric_limits<float>::infinity();
  const float ox = eye.x() - can.x, oy = eye.y() - can.y;
  const float a = ray.x() * ray.x() + ray.y() * ray.y();
  const float b = 2 * (ox * ray.x() + oy * ray.y());
  const float c = ox * ox + oy * oy - can.radius * can.radius;
  const float disc = b * b - 4 * a * c;
  if (a > 0 && disc >= 0) {
    const float t = (-b - std::sqrt(disc)) / (2 * a);
    const float z = eye.z() + t * ray.z();
    if (t > 0 && z >= can.base && z <= can.top) nearest = t;
  }
  if (ray.z() < 0) {  // the lid
    const float t = (can.top - eye.z()) / ray.z();
    const Vec3f p = eye + t * ray;
    if (std::hypot(p.x() - can.x, p.y() - can.y) <= can.radius) nearest = std::min(nearest, t);
  }
  return nearest;
}

// A 640 x 480 Kinect-like organised scan of a 1.2 x 1.3 m table (z = 0) from above and in front,
// with mOSD labels (1 table, 10k+ object k) and colours.
PointCloud scan(const std::vector<Box>& boxes, const std::vector<Can>& cans = {}) {
  const int width = 640, height = 480;
  const float focal = 525.0f;
  const Vec3f eye(0.0f, -0.7f, 0.6f), target(0.0f, 0.2f, 0.0f);
  const Vec3f forward = (target - eye).normalized();
  const Vec3f right = forward.cross(Vec3f::UnitZ()).normalized();
  const Vec3f down = forward.cross(right);
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, 0.0005f);
  PointCloud cloud;
  cloud.width = width;
  cloud.height = height;
  cloud.viewpoint.origin = eye;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      const Vec3f ray =
          (forward + (c - width / 2.0f) / focal * right + (r - height / 2.0f) / focal * down)
              .normalized();
      float nearest = std::numeric_limits<float>::infinity();
      std::uint32_t label = 0, rgb = 0;
      if (ray.z() < 0) {
        const float t = -eye.z() / ray.z();
        const Vec3f p = eye + t * ray;
        if (std::abs(p.x()) < 0.6f && p.y() > -0.3f && p.y() < 1.0f) {
          nearest = t;
          label = 1;
          rgb = 0xC8B496;
        }
      }
      for (const Box& box : boxes) {  // slab test
        float t0 = 0.0f, t1 = std::numeric_limits<float>::infinity();
        for (int a = 0; a < 3; ++a) {
          const float ta = (box.lo[a] - eye[a]) / ray[a], tb = (box.hi[a] - eye[a]) / ray[a];
          t0 = std::max(t0, std::min(ta, tb));
          t1 = std::min(t1, std::max(ta, tb));
        }
        if (t0 <= t1 && t0 < nearest) {
          nearest = t0;
          label = box.label;
          rgb = box.rgb;
        }
      }
      for (const Can& can : cans) {
        const float t = hit_can(can, eye, ray);
        if (t < nearest) {
          nearest = t;
          label = can.label;
          rgb = can.rgb;
        }
      }
      const bool hit = std::isfinite(nearest);
      const Vec3f p = hit ? Vec3f(eye + nearest * ray + Vec3f(noise(rng), noise(rng), noise(rng)))
                          : Vec3f(nan, nan, nan);
      cloud.xyz.push_back(p);
      cloud.labels.push_back(hit ? label : 0);
      cloud.rgba.push_back(0xFF000000u | rgb);
    }
  return cloud;
}

TabletopOptions given_up(bool creases = true) {
  TabletopOptions options;
  options.up_source = UpAxisSource::kGiven;
  options.up = Vec3f::UnitZ();
  options.creases.enabled = creases;
  return options;
}

// Euclidean clustering joins the touching objects into one cluster; the crease cut separates
// them, each object then matching one cluster closely.
void expect_split(const PointCloud& cloud, std::size_t objects) {
  const TabletopResult joined = segment_tabletop(cloud, given_up(false), RunContext{2});
  ASSERT_TRUE(joined.ok()) << joined.message;
  EXPECT_LT(joined.clusters.size(), objects) << "the scene does not test a crease";
  const TabletopResult split = segment_tabletop(cloud, given_up(), RunContext{2});
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
