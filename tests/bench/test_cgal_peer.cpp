// The CGAL Efficient RANSAC peer (bench/cgal_ransac_peer.hpp) on a tiny cloud of known shapes:
// a 20 x 12 cm plane and, beside it, a 40 mm cylinder, sampled at 3 mm with 0.3 mm noise and
// their exact normals. CGAL's shapes, converted to primlabel Primitives, come back with the
// right parameters and the shared matcher finds both true instances; degenerate CGAL shapes (a
// can as a torus of kilometres' major radius) come back as the shape they tend to. Built only
// with CGAL.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cgal_ransac_peer.hpp"
#include "primitive_matching.hpp"
#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel {
namespace {

using Vec3d = Eigen::Vector3d;

constexpr double kSpacing = 0.003;
constexpr double kRadius = 0.04;
const Vec3d kAxis = Vec3d(0.3, 0.1, 1).normalized();  // a tilted can
const Vec3d kBase(0.35, 0.1, 0.0);

struct Cloud {
  std::vector<Vec3f> xyz, normals;
  std::vector<float> object;
};

Cloud plane_and_cylinder() {
  Cloud c;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 0.0003);
  for (double x = 0; x < 0.2; x += kSpacing)
    for (double y = 0; y < 0.12; y += kSpacing) {
      c.xyz.push_back(Vec3d(x, y, noise(rng)).cast<float>());
      c.normals.push_back(Vec3f::UnitZ());
      c.object.push_back(0);
    }
  const Vec3d u = kAxis.unitOrthogonal(), v = kAxis.cross(u);
  const int around = int(2 * M_PI * kRadius / kSpacing);
  for (double h = 0; h < 0.12; h += kSpacing)
    for (int k = 0; k < around; ++k) {
      const double a = 2 * M_PI * k / around;
      const Vec3d out = std::cos(a) * u + std::sin(a) * v;
      c.xyz.push_back((kBase + h * kAxis + (kRadius + noise(rng)) * out).cast<float>());
      c.normals.push_back(out.cast<float>());
      c.object.push_back(1);
    }
  return c;
}

std::vector<synth::TruePrimitive> truth() {
  primitives::Primitive plane;
  plane.class_id = class_id(PrimitiveClass::kPlane);
  plane.model = primitives::PlaneModel{
      Vec3d::UnitZ(), 0, {0.1, 0.1, 0}, Vec3d::UnitX(), Vec3d::UnitY(), 0.2, 0.2};
  plane.points = 1000;
  primitives::Primitive cylinder;
  cylinder.class_id = class_id(PrimitiveClass::kCylinderConvex);
  cylinder.model = primitives::CylinderModel{kBase + 0.06 * kAxis, kAxis, kRadius, 0.12};
  cylinder.points = 1000;
  return {{0, plane, plane.points}, {1, cylinder, cylinder.points}};  // all points their own
}

TEST(CgalPeer, FindsThePlaneAndTheCylinderWithTheirParameters) {
  const Cloud c = plane_and_cylinder();
  const auto parameters = bench::CgalRansacParameters::for_spacing(kSpacing);
  EXPECT_DOUBLE_EQ(parameters.cluster_epsilon, 4 * kSpacing);
  const bench::CgalDetections found = bench::detect_with_cgal(c.xyz, c.normals, parameters);
  ASSERT_FALSE(found.set.primitives.empty());
  ASSERT_EQ(found.set.point_segment.size(), c.xyz.size());

  // Every assigned point names a primitive, and each primitive's count is its points'.
  std::vector<std::size_t> counted(found.set.primitives.size(), 0);
  for (const auto s : found.set.point_segment)
    if (s != primitives::kNoSegment) {
      ASSERT_LT(s, counted.size());
      ++counted[s];
    }
  for (std::size_t k = 0; k < counted.size(); ++k) {
    EXPECT_EQ(counted[k], found.set.primitives[k].points);
    if (k > 0) {
      EXPECT_GE(found.set.primitives[k - 1].points, found.set.primitives[k].points);
    }
  }

  const bench::InstanceMatch m =
      bench::match_instances(found.set, c.xyz, c.object, truth(), bench::MatchOptions{});
  EXPECT_EQ(m.found, 2u);
  EXPECT_EQ(m.correct, m.detections);  // nothing else detected
  for (const bench::MatchedPair& pair : m.pairs) {
    const primitives::Primitive& p = found.set.primitives[pair.detection];
    if (const auto* cyl = std::get_if<primitives::CylinderModel>(&p.model)) {
      EXPECT_NEAR(cyl->radius, kRadius, 0.001);
      EXPECT_LT(bench::axis_angle_deg(cyl->axis, kAxis), 2.0);
      EXPECT_NEAR(cyl->height, 0.12, 0.01);
      EXPECT_EQ(p.class_id, class_id(PrimitiveClass::kCylinderConvex));  // normals point out
      EXPECT_LT(p.rms, 0.001);
    } else {
      const auto& plane = std::get<primitives::PlaneModel>(p.model);
      EXPECT_LT(bench::axis_angle_deg(plane.normal, Vec3d::UnitZ()), 1.0);
      EXPECT_NEAR(plane.normal.dot(Vec3d(0.1, 0.06, 0)) + plane.offset, 0, 0.001);
      EXPECT_NEAR(plane.extent_u, 0.2, 0.01);
      EXPECT_NEAR(plane.extent_v, 0.12, 0.01);
      EXPECT_LT(bench::axis_angle_deg(plane.axis_u, Vec3d::UnitX()), 2.0);
      EXPECT_EQ(p.class_id, class_id(PrimitiveClass::kPlane));
    }
  }
}

// CGAL's tori of kilometres and cylinders of tens of metres are the cylinder and plane they tend
// to near the points.
TEST(CgalPeer, DegenerateShapesBecomeTheirLimit) {
  const Cloud c = plane_and_cylinder();
  std::vector<std::uint32_t> plane_points, cylinder_points;
  for (std::uint32_t i = 0; i < c.xyz.size(); ++i)
    (c.object[i] == 0 ? plane_points : cylinder_points).push_back(i);

  const Vec3d across = kAxis.unitOrthogonal(), out = across.cross(kAxis);
  const double major = 1000;
  const primitives::TorusModel torus{kBase + 0.06 * kAxis - major * out, across, major, kRadius};
  const auto as_cylinder = bench::degenerate_limit(torus, c.xyz, cylinder_points, 2.0);
  const auto* cylinder = std::get_if<primitives::CylinderModel>(&as_cylinder);
  ASSERT_NE(cylinder, nullptr);
  EXPECT_DOUBLE_EQ(cylinder->radius, kRadius);
  EXPECT_LT(bench::axis_angle_deg(cylinder->axis, kAxis), 0.01);
  EXPECT_NEAR(cylinder->height, 0.12, 0.005);
  EXPECT_LT((cylinder->center - (kBase + 0.06 * kAxis)).norm(), 0.005);

  const primitives::CylinderModel wide{{0.1, 0.06, -30}, Vec3d::UnitX(), 30, 0.2};
  const auto as_plane = bench::degenerate_limit(wide, c.xyz, plane_points, 2.0);
  const auto* plane = std::get_if<primitives::PlaneModel>(&as_plane);
  ASSERT_NE(plane, nullptr);
  EXPECT_LT(bench::axis_angle_deg(plane->normal, Vec3d::UnitZ()), 0.01);
  EXPECT_NEAR(plane->offset, 0, 1e-4);
  EXPECT_NEAR(plane->extent_u, 0.2, 0.01);

  // Under the limit, or with the limit off, a shape stays what CGAL found.
  const primitives::SphereModel ball{{0, 0, 0}, 1.5};
  EXPECT_TRUE(std::holds_alternative<primitives::SphereModel>(
      bench::degenerate_limit(ball, c.xyz, plane_points, 2.0)));
  EXPECT_TRUE(std::holds_alternative<primitives::TorusModel>(
      bench::degenerate_limit(torus, c.xyz, cylinder_points, 0)));
}

TEST(CgalPeer, SameSeedSameShapes) {
  const Cloud c = plane_and_cylinder();
  const auto parameters = bench::CgalRansacParameters::for_spacing(kSpacing);
  const auto a = bench::detect_with_cgal(c.xyz, c.normals, parameters);
  const auto b = bench::detect_with_cgal(c.xyz, c.normals, parameters);
  EXPECT_EQ(a.set.point_segment, b.set.point_segment);
}

TEST(CgalPeer, RejectsMissingNormalsAndSkipsNonFinitePoints) {
  Cloud c = plane_and_cylinder();
  EXPECT_THROW(bench::detect_with_cgal(c.xyz, std::span<const Vec3f>(c.normals).first(3), {}),
               std::invalid_argument);
  c.xyz[0] = Vec3f::Constant(std::nanf(""));
  c.normals[1] = Vec3f::Constant(std::nanf(""));
  const auto found = bench::detect_with_cgal(c.xyz, c.normals, {});
  EXPECT_EQ(found.set.point_segment[0], primitives::kNoSegment);
  EXPECT_EQ(found.set.point_segment[1], primitives::kNoSegment);
}

}  // namespace
}  // namespace primlabel
