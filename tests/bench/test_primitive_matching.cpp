// The instance matching every detector of `primlabel-bench primitives` is scored with
// (bench/primitive_matching.hpp): a detection counts once, on the true primitive of its kind and
// object most of its points lie on; duplicates, wrong kinds and detections off every true surface
// and detections whose parameters are far off the surface they lie on count against precision
// only.

#include <gtest/gtest.h>

#include <cmath>

#include "primitive_matching.hpp"
#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel {
namespace {

using primitives::CylinderModel;
using primitives::PlaneModel;
using primitives::Primitive;
using primitives::SphereModel;
using Vec3d = Eigen::Vector3d;

// A tiny scene: object 1 a table plane z = 0, object 2 a mug of outer radius 40 mm and inner
// radius 35 mm (axis z through (0.5, 0)); points added by the test, each with its object.
struct Scene {
  std::vector<synth::TruePrimitive> truth;
  std::vector<Vec3f> xyz;
  std::vector<float> object;
  primitives::PrimitiveSet detected;

  Scene() {
    Primitive plane;
    plane.class_id = class_id(PrimitiveClass::kPlane);
    plane.model =
        PlaneModel{Vec3d::UnitZ(), 0, Vec3d::Zero(), Vec3d::UnitX(), Vec3d::UnitY(), 1, 1};
    plane.points = 100;
    Primitive outer;
    outer.class_id = class_id(PrimitiveClass::kCylinderConvex);
    outer.model = CylinderModel{{0.5, 0, 0.05}, Vec3d::UnitZ(), 0.04, 0.1};
    outer.points = 100;
    Primitive inner = outer;
    inner.class_id = class_id(PrimitiveClass::kCylinderConcave);
    inner.model = CylinderModel{{0.5, 0, 0.05}, Vec3d::UnitZ(), 0.035, 0.1};
    inner.points = 10;  // under min_true_points: not in the recall
    truth = {{1, plane, plane.points}, {2, outer, outer.points}, {2, inner, inner.points}};
  }

  // n points of `object` as detection `segment` (kNoSegment: none), from `at(k)`.
  template <class At>
  void add(std::size_t n, int owner, std::uint32_t segment, At at) {
    for (std::size_t k = 0; k < n; ++k) {
      xyz.push_back(at(double(k) / double(n)).template cast<float>());
      object.push_back(float(owner));
      detected.point_segment.push_back(segment);
    }
  }
  std::uint32_t detection(primitives::Model model) {
    Primitive p;
    p.model = std::move(model);
    detected.primitives.push_back(p);
    return std::uint32_t(detected.primitives.size() - 1);
  }
};

Vec3d on_plane(double t) { return {0.3 * t, 0.1 + 0.2 * std::sin(40 * t), 0.0005}; }
Vec3d on_circle(double radius, double t) {
  return {0.5 + radius * std::cos(3 * t), radius * std::sin(3 * t), 0.01 + 0.08 * t};
}

TEST(PrimitiveMatching, CountsEachTrueInstanceOnceAndNoWrongDetection) {
  Scene s;
  const Vec3d tilted = Vec3d(std::sin(0.02), 0, std::cos(0.02));  // 1.15 degrees off z
  const auto cylinder = s.detection(CylinderModel{{0.5, 0, 0.05}, tilted, 0.041, 0.1});
  const auto duplicate = s.detection(CylinderModel{{0.5, 0, 0.05}, Vec3d::UnitZ(), 0.04, 0.1});
  const auto wrong_kind = s.detection(SphereModel{{0.1, 0.1, -1}, 1});
  const auto off_surface = s.detection(CylinderModel{{0.5, 0, 0.05}, Vec3d::UnitZ(), 0.05, 0.1});
  const auto other_object = s.detection(PlaneModel{});
  const auto plane = s.detection(PlaneModel{});
  // On the plane's points but 30 degrees off: a wrong instance, however many points it has.
  const auto tilted_plane =
      s.detection(PlaneModel{Vec3d(0, std::sin(M_PI / 6), std::cos(M_PI / 6)), 0, Vec3d::Zero(),
                             Vec3d::UnitX(), Vec3d::UnitY(), 1, 1});
  // On the outer wall's points but 15 mm too wide.
  const auto wide = s.detection(CylinderModel{{0.5, 0, 0.05}, Vec3d::UnitZ(), 0.055, 0.1});
  const auto tiny = s.detection(PlaneModel{});
  s.add(120, 2, cylinder, [](double t) { return on_circle(0.04, t); });
  s.add(60, 2, duplicate, [](double t) { return on_circle(0.0401, t); });
  s.add(80, 1, wrong_kind, on_plane);
  s.add(80, 2, off_surface, [](double t) { return on_circle(0.05, t); });  // 10 mm out
  s.add(80, 3, other_object, on_plane);  // on the plane's surface but another object's points
  s.add(150, 1, plane, on_plane);
  s.add(200, 1, tilted_plane, on_plane);
  s.add(200, 2, wide, [](double t) { return on_circle(0.04, t); });
  s.add(20, 1, tiny, on_plane);  // under min_detection_points: not scored
  s.add(30, 1, primitives::kNoSegment, on_plane);

  const bench::InstanceMatch m = bench::match_instances(s.detected, s.xyz, s.object, s.truth);
  EXPECT_EQ(m.true_instances, 2u);  // the plane and the outer wall
  EXPECT_EQ(m.found, 2u);
  EXPECT_EQ(m.detections, 8u);  // all but the tiny one
  EXPECT_EQ(m.correct, 2u);
  ASSERT_EQ(m.pairs.size(), 2u);
  EXPECT_EQ(m.pairs[0].truth, 0u);
  EXPECT_EQ(m.pairs[0].detection, plane);
  EXPECT_EQ(m.pairs[1].truth, 1u);
  EXPECT_EQ(m.pairs[1].detection, cylinder);  // the larger of the two on the outer wall
  EXPECT_NEAR(m.pairs[1].radius_error, 0.001, 1e-9);
  EXPECT_NEAR(m.pairs[1].axis_error_deg, 0.02 * 180 / M_PI, 1e-6);
}

TEST(PrimitiveMatching, ADetectionGoesToTheSurfaceMostOfItsPointsAreOn) {
  Scene s;
  s.truth[2].primitive.points = s.truth[2].own_points = 100;  // the inner wall counts now
  const auto d = s.detection(CylinderModel{{0.5, 0, 0.05}, Vec3d::UnitZ(), 0.035, 0.1});
  s.add(40, 2, d, [](double t) { return on_circle(0.04, t); });
  s.add(70, 2, d, [](double t) { return on_circle(0.035, t); });
  const bench::InstanceMatch m = bench::match_instances(s.detected, s.xyz, s.object, s.truth);
  EXPECT_EQ(m.true_instances, 3u);
  EXPECT_EQ(m.found, 1u);
  ASSERT_EQ(m.pairs.size(), 1u);
  EXPECT_EQ(m.pairs[0].truth, 2u);  // inner, not outer
  EXPECT_NEAR(m.pairs[0].radius_error, 0, 1e-12);
}

// A face the scan never sees still has the adjacent faces' points within the tolerance of its
// edge in its listed count; it is visible, and in the recall, only by points of its own.
TEST(PrimitiveMatching, RecallCountsTruePrimitivesVisibleByPointsOfTheirOwn) {
  Scene s;
  s.truth[2].primitive.points = 100;  // listed: 100 points within the tolerance
  s.truth[2].own_points = 49;         // but under 50 of them nearer to it than to the outer wall
  const auto d = s.detection(CylinderModel{{0.5, 0, 0.05}, Vec3d::UnitZ(), 0.04, 0.1});
  s.add(100, 2, d, [](double t) { return on_circle(0.04, t); });
  bench::InstanceMatch m = bench::match_instances(s.detected, s.xyz, s.object, s.truth);
  EXPECT_EQ(m.true_instances, 2u);  // the plane and the outer wall
  EXPECT_EQ(m.found, 1u);
  EXPECT_EQ(m.listed_instances, 3u);
  EXPECT_EQ(m.listed_found, 1u);
  EXPECT_TRUE(bench::visible(s.truth[1], {}));
  EXPECT_FALSE(bench::visible(s.truth[2], {}));
  s.truth[2].own_points = 50;
  m = bench::match_instances(s.detected, s.xyz, s.object, s.truth);
  EXPECT_EQ(m.true_instances, 3u);
}

TEST(PrimitiveMatching, MismatchedSizesAreRejected) {
  Scene s;
  s.xyz.push_back(Vec3f::Zero());
  EXPECT_THROW(bench::match_instances(s.detected, s.xyz, s.object, s.truth), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel
