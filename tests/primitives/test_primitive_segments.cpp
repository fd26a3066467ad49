// Segmentation by label, the whole set of primitives of a labeled cloud (the same for any thread
// count) and its JSON read back.

#include <gtest/gtest.h>

#include <limits>

#include "primitive_samples.hpp"
#include "primlabel/geometry/point_spacing.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/primitives/fit_primitives.hpp"
#include "primlabel/primitives/primitives_json.hpp"
#include "primlabel/primitives/segmentation.hpp"

namespace primlabel::primitives {
namespace {

using test::SampleMaker;
using test::Samples;
using V = Eigen::Vector3d;

constexpr std::uint32_t kPlane = class_id(PrimitiveClass::kPlane);
constexpr std::uint32_t kCylinder = class_id(PrimitiveClass::kCylinderConvex);
constexpr std::uint32_t kSphere = class_id(PrimitiveClass::kSphereConvex);
constexpr std::uint32_t kCorner = class_id(PrimitiveClass::kCorner);

// A grid patch of `label` points at z, from (x0, y0), n x n points 2 mm apart.
void add_grid(std::vector<Vec3f>& xyz, std::vector<std::uint32_t>& labels, float x0, float y0,
              float z, int n, std::uint32_t label) {
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      xyz.emplace_back(x0 + 0.002f * i, y0 + 0.002f * j, z);
      labels.push_back(label);
    }
}

TEST(Segmentation, ComponentsBySizeThenLowestIndex) {
  std::vector<Vec3f> xyz;
  std::vector<std::uint32_t> labels;
  add_grid(xyz, labels, 0.0f, 0.0f, 0.0f, 10, kPlane);      // 100 points, 0..99
  add_grid(xyz, labels, 0.5f, 0.0f, 0.0f, 20, kPlane);      // 400, far away: its own segment
  add_grid(xyz, labels, 0.0f, 0.0202f, 0.0f, 10, kCorner);  // 100, touching the first, other label
  add_grid(xyz, labels, 0.9f, 0.0f, 0.0f, 10, kPlane);      // 100, ties the first in size
  add_grid(xyz, labels, 2.0f, 0.0f, 0.0f, 3, kPlane);       // 9: below min_points
  add_grid(xyz, labels, 3.0f, 0.0f, 0.0f, 10, 0);           // unknown: no segment
  xyz.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
  labels.push_back(kPlane);
  SegmentOptions options;
  options.radius = 0.005f;
  const Segmentation s = segment_by_label(xyz, labels, options);
  ASSERT_EQ(s.segments.size(), 4u);
  EXPECT_EQ(s.segments[0].size(), 400u);
  EXPECT_EQ(s.segments[0].front(), 100u);
  EXPECT_EQ(s.segments[1].front(), 0u);    // 100 points, lowest index first
  EXPECT_EQ(s.segments[2].front(), 500u);  // the corner patch
  EXPECT_EQ(s.labels[2], kCorner);
  EXPECT_EQ(s.segments[3].front(), 600u);
  EXPECT_EQ(s.point_segment[0], 1u);
  EXPECT_EQ(s.point_segment[150], 0u);
  EXPECT_EQ(s.point_segment[700], kNoSegment);    // too small
  EXPECT_EQ(s.point_segment[720], kNoSegment);    // unknown
  EXPECT_EQ(s.point_segment.back(), kNoSegment);  // NaN
  options.max_segments = 2;
  EXPECT_EQ(segment_by_label(xyz, labels, options).segments.size(), 2u);
}

TEST(Segmentation, AutomaticRadiusAndBadInput) {
  std::vector<Vec3f> xyz;
  std::vector<std::uint32_t> labels;
  add_grid(xyz, labels, 0.0f, 0.0f, 0.0f, 10, kPlane);
  const Segmentation s = segment_by_label(xyz, labels, SegmentOptions{});
  EXPECT_NEAR(s.radius, 0.008f, 1e-4f);  // 4x the 2 mm spacing
  ASSERT_EQ(s.segments.size(), 1u);
  EXPECT_THROW(segment_by_label(xyz, std::vector<std::uint32_t>(3, 1), SegmentOptions{}),
               std::invalid_argument);
  EXPECT_TRUE(segment_by_label({}, {}, SegmentOptions{}).segments.empty());
  // Coincident points: one segment, no spacing to measure.
  const std::vector<Vec3f> same(5000, Vec3f(1, 2, 3));
  EXPECT_EQ(segment_by_label(same, std::vector<std::uint32_t>(5000, kSphere), SegmentOptions{})
                .segments.size(),
            1u);
}

// A table with a can and a ball on it, labeled by construction.
struct Scene {
  Samples samples;
  std::vector<std::uint32_t> labels;
};

Scene make_scene() {
  SampleMaker m(11);
  Scene scene;
  for (int i = 0; i < 6000; ++i) {
    m.add(scene.samples, V(m.uniform(-0.3, 0.3), m.uniform(-0.3, 0.3), 0), V::UnitZ());
    scene.labels.push_back(kPlane);
  }
  const std::size_t before_can = scene.samples.xyz.size();
  test::add_cylinder(scene.samples, m, V(0.1, 0.1, 0.03), V::UnitZ(), 0.033, 0.09, M_PI, 3000);
  scene.labels.resize(scene.samples.xyz.size(), kCylinder);
  test::add_sphere(scene.samples, m, V(-0.1, -0.1, 0.1), 0.035, V(0, -1, 1).normalized(),
                   80 * M_PI / 180, 2000);
  scene.labels.resize(scene.samples.xyz.size(), kSphere);
  EXPECT_EQ(before_can, 6000u);
  return scene;
}

TEST(FitPrimitives, SceneOfKnownShapesAnyThreadCount) {
  const Scene scene = make_scene();
  PrimitiveOptions options;
  options.segments.radius = 0.02f;
  const PrimitiveSet one = fit_primitives(scene.samples.xyz, scene.samples.normals, scene.labels,
                                          options, RunContext{1});
  const PrimitiveSet two = fit_primitives(scene.samples.xyz, scene.samples.normals, scene.labels,
                                          options, RunContext{2});
  ASSERT_EQ(one.primitives.size(), 3u);
  EXPECT_EQ(one.primitives[0].kind(), PrimitiveKind::kPlane);
  EXPECT_EQ(one.primitives[1].kind(), PrimitiveKind::kCylinder);
  EXPECT_EQ(one.primitives[2].kind(), PrimitiveKind::kSphere);
  EXPECT_NEAR(std::get<CylinderModel>(one.primitives[1].model).radius, 0.033, 0.0005);
  EXPECT_NEAR(std::get<SphereModel>(one.primitives[2].model).radius, 0.035, 0.0005);
  EXPECT_EQ(one.point_segment[0], 0u);
  EXPECT_EQ(one.point_segment[6000], 1u);
  // Bit for bit the same with two threads.
  EXPECT_EQ(one.point_segment, two.point_segment);
  ASSERT_EQ(two.primitives.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(primitives_json(std::span(&one.primitives[k], 1)),
              primitives_json(std::span(&two.primitives[k], 1)));
    EXPECT_EQ(one.primitives[k].rms, two.primitives[k].rms);
  }
}

// What the labeling pipeline shares (its index, its radius lists, kept whole or in part, and its
// point spacing) gives the segments and fits a search of segment_by_label's own gives, at 1 and
// 2 threads; lists of a smaller radius than the linking one are not used.
TEST(FitPrimitives, SharedNeighbourListsGiveTheSameSegmentsAndFits) {
  const Scene scene = make_scene();
  const std::vector<Vec3f>& xyz = scene.samples.xyz;
  const PrimitiveOptions options;  // automatic linking radius, the default cap
  const PrimitiveSet own =
      fit_primitives(xyz, scene.samples.normals, scene.labels, options, RunContext{1});
  ASSERT_GE(own.primitives.size(), 3u);
  const NeighborSearch search(xyz);
  const float spacing = median_point_spacing(xyz, search);
  const float linking = own.segment_radius;
  ASSERT_NEAR(linking, 4 * spacing, 1e-6f);
  const NeighborLists whole(xyz, search, Neighborhood::Hybrid(2 * linking, 1024), 1u << 30);
  const NeighborLists part(xyz, search, Neighborhood::Hybrid(2 * linking, 1024), 200000);
  const NeighborLists narrow(xyz, search, Neighborhood::Hybrid(0.5f * linking, 1024), 1u << 30);
  ASSERT_EQ(whole.kept_points(), xyz.size());
  ASSERT_GT(part.kept_points(), 0u);
  ASSERT_LT(part.kept_points(), xyz.size());
  for (const NeighborLists* lists : {&whole, &part, &narrow, (const NeighborLists*)nullptr})
    for (int threads : {1, 2}) {
      const PrimitiveSet shared = fit_primitives(xyz, scene.samples.normals, scene.labels, options,
                                                 RunContext{threads}, {&search, lists, spacing});
      EXPECT_EQ(shared.segment_radius, own.segment_radius);
      EXPECT_EQ(shared.point_segment, own.point_segment) << threads;
      ASSERT_EQ(shared.primitives.size(), own.primitives.size());
      EXPECT_EQ(primitives_json(shared.primitives), primitives_json(own.primitives));
    }
}

TEST(FitPrimitives, CornersAndFailedFitsKeepTheirSegment) {
  std::vector<Vec3f> xyz;
  std::vector<std::uint32_t> labels;
  add_grid(xyz, labels, 0.0f, 0.0f, 0.0f, 10, kCorner);
  add_grid(xyz, labels, 1.0f, 0.0f, 0.0f, 10, kSphere);  // flat: no normals, no sphere
  const PrimitiveSet set = fit_primitives(xyz, {}, labels, PrimitiveOptions{});
  ASSERT_EQ(set.primitives.size(), 2u);
  for (const Primitive& p : set.primitives) {
    EXPECT_EQ(p.kind(), PrimitiveKind::kSegment);
    EXPECT_EQ(p.confidence, 0.0);
    EXPECT_EQ(p.points, 100u);
  }
  EXPECT_NEAR(set.primitives[0].centroid.x(), 0.009, 1e-6);
  EXPECT_NEAR(set.primitives[1].bounds_max.x(), 1.018, 1e-6);
  EXPECT_THROW(fit_primitives(xyz, std::vector<Vec3f>(3), labels, PrimitiveOptions{}),
               std::invalid_argument);
}

TEST(PrimitivesJson, ReadsBackWhatItWrites) {
  const Scene scene = make_scene();
  PrimitiveOptions options;
  options.segments.radius = 0.02f;
  const PrimitiveSet set =
      fit_primitives(scene.samples.xyz, scene.samples.normals, scene.labels, options);
  const std::string text = primitives_json(set.primitives);
  const std::vector<Primitive> back = parse_primitives_json(text);
  ASSERT_EQ(back.size(), set.primitives.size());
  for (std::size_t k = 0; k < back.size(); ++k) {
    EXPECT_EQ(back[k].kind(), set.primitives[k].kind());
    EXPECT_EQ(back[k].class_id, set.primitives[k].class_id);
    EXPECT_EQ(back[k].points, set.primitives[k].points);
    EXPECT_EQ(back[k].inliers, set.primitives[k].inliers);
    EXPECT_NEAR(back[k].rms, set.primitives[k].rms, 1e-6 * set.primitives[k].rms + 1e-12);
  }
  EXPECT_NEAR(std::get<CylinderModel>(back[1].model).radius,
              std::get<CylinderModel>(set.primitives[1].model).radius, 1e-8);
  EXPECT_NE(text.find("\"kind\": \"cylinder\""), std::string::npos);
  EXPECT_THROW(parse_primitives_json("{\"primitives\": [{\"kind\": \"cone\"}]}"),
               std::invalid_argument);
  EXPECT_THROW(parse_primitives_json("not json"), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::primitives
