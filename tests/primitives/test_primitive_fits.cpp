// Each model fitted to synthetic points with known parameters, noise (0.5 mm), tilted normals
// and outliers; the bounds are far below what a wrong model or a missed refinement gives. Then
// segments no fit can use: empty, tiny, coincident, NaN.

#include <gtest/gtest.h>

#include <limits>

#include "primitive_samples.hpp"
#include "primlabel/primitives/fitters.hpp"

namespace primlabel::primitives {
namespace {

using test::angle_deg;
using test::line_distance;
using test::SampleMaker;
using test::Samples;
using V = Eigen::Vector3d;

std::optional<Fit> fit(PrimitiveKind kind, const Samples& s, std::uint64_t seed = 1) {
  const std::vector<std::uint32_t> idx = s.indices();
  return fit_model(kind, SegmentPoints{s.xyz, s.normals, idx}, FitSettings{}, seed);
}

TEST(PrimitiveFit, PlaneNormalOffsetAndExtent) {
  SampleMaker m(1);
  Samples s;
  const V normal = V(0.3, 0.2, 0.93).normalized(), center(0.4, -0.2, 0.8);
  const auto [u, v] = test::basis(normal);
  for (int i = 0; i < 3000; ++i)
    m.add(s, center + m.uniform(-0.2, 0.2) * u + m.uniform(-0.05, 0.05) * v, normal);
  m.add_outliers(s, 600, center - V(0.2, 0.2, 0.2), center + V(0.2, 0.2, 0.2));
  const auto f = fit(PrimitiveKind::kPlane, s);
  ASSERT_TRUE(f);
  const auto& plane = std::get<PlaneModel>(f->model);
  EXPECT_LT(angle_deg(plane.normal, normal), 0.3);
  EXPECT_NEAR(plane.normal.dot(center) + plane.offset, 0.0, 0.0005);
  EXPECT_NEAR(plane.extent_u, 0.4, 0.01);
  EXPECT_NEAR(plane.extent_v, 0.1, 0.01);
  EXPECT_LT(angle_deg(plane.axis_u, u), 2.0);
  EXPECT_LT((plane.center - center).norm(), 0.005);
  EXPECT_GT(plane.normal.dot(normal), 0);  // faces the points' normals
  EXPECT_GE(f->inliers, 2950u);
  EXPECT_LT(f->inliers, 3100u);
  EXPECT_LT(f->rms, 0.0008);
  EXPECT_NEAR(f->confidence, 3000.0 / 3600.0, 0.03);
}

// A near-square table seen with more points along a diagonal (as a sensor's density varies):
// its principal axes run along the diagonal, but the drawn extent is the table's own rectangle,
// not a box around it twice its area.
TEST(PrimitiveFit, PlaneExtentIsTheSmallestRectangleNotThePrincipalAxesBox) {
  SampleMaker m(2);
  Samples s;
  const V normal = V(0.1, -0.2, 0.97).normalized(), center(0.1, 0.3, 0.7);
  const auto [u, v] = test::basis(normal);
  for (int i = 0; i < 3000; ++i)
    m.add(s, center + m.uniform(-0.3, 0.3) * u + m.uniform(-0.25, 0.25) * v, normal);
  for (int i = 0; i < 3000; ++i) {
    const double t = m.uniform(-0.25, 0.25);
    m.add(s, center + (t + m.uniform(-0.02, 0.02)) * u + t * v, normal);
  }
  const auto f = fit(PrimitiveKind::kPlane, s);
  ASSERT_TRUE(f);
  const auto& plane = std::get<PlaneModel>(f->model);
  EXPECT_NEAR(plane.extent_u, 0.6, 0.01);
  EXPECT_NEAR(plane.extent_v, 0.5, 0.01);
  EXPECT_LT(std::min(angle_deg(plane.axis_u, u), angle_deg(plane.axis_u, -u)), 2.0);
  EXPECT_LT((plane.center - center).norm(), 0.01);
  EXPECT_NEAR(plane.axis_u.cross(plane.axis_v).dot(plane.normal), 1.0, 1e-9);
}

TEST(PrimitiveFit, ConvexCylinderSeenOverHalfTurn) {
  SampleMaker m(2);
  Samples s;
  const V axis = V(0.2, -0.1, 1).normalized(), base(0.1, 0.3, 0.7);
  test::add_cylinder(s, m, base, axis, 0.04, 0.12, M_PI, 3000);
  m.add_outliers(s, 300, base - V(0.1, 0.1, 0.1), base + V(0.1, 0.1, 0.2));
  const auto f = fit(PrimitiveKind::kCylinder, s);
  ASSERT_TRUE(f);
  const auto& c = std::get<CylinderModel>(f->model);
  EXPECT_NEAR(c.radius, 0.04, 0.0005);
  EXPECT_LT(angle_deg(c.axis, axis), 0.5);
  EXPECT_LT(line_distance(c.center, base, axis), 0.0005);
  EXPECT_NEAR(c.height, 0.12, 0.005);
  EXPECT_LT(line_distance(base + 0.06 * axis, c.center, c.axis), 0.001);
  EXPECT_NEAR((c.center - base).dot(axis), 0.06, 0.003);
  EXPECT_GT(f->confidence, 0.8);  // 3000 of 3300 inliers over the full half turn
}

TEST(PrimitiveFit, ConcaveCylinderInsideAMug) {
  SampleMaker m(3);
  Samples s;
  const V axis = V::UnitZ(), base(0, 0, 0);
  test::add_cylinder(s, m, base, axis, 0.035, 0.08, 0.6 * M_PI, 2000, true);
  const auto f = fit(PrimitiveKind::kCylinder, s);
  ASSERT_TRUE(f);
  const auto& c = std::get<CylinderModel>(f->model);
  EXPECT_NEAR(c.radius, 0.035, 0.0005);
  EXPECT_LT(angle_deg(c.axis, axis), 0.5);
  EXPECT_GT(c.axis.z(), 0);  // the canonical direction
  EXPECT_LT(line_distance(c.center, base, axis), 0.0005);
  EXPECT_NEAR(f->confidence, 0.6, 0.05);  // inlier share 1 times an arc of 0.6 half turns
}

TEST(PrimitiveFit, SphereCapCentreAndRadius) {
  SampleMaker m(4);
  Samples s;
  const V center(0.2, 0.1, 0.5);
  test::add_sphere(s, m, center, 0.05, V(0.3, -0.4, 0.8).normalized(), 60 * M_PI / 180, 2000);
  m.add_outliers(s, 200, center - V(0.08, 0.08, 0.08), center + V(0.08, 0.08, 0.08));
  const auto f = fit(PrimitiveKind::kSphere, s);
  ASSERT_TRUE(f);
  const auto& sphere = std::get<SphereModel>(f->model);
  EXPECT_LT((sphere.center - center).norm(), 0.0008);
  EXPECT_NEAR(sphere.radius, 0.05, 0.0005);
  // A 60 degree cap of a hemisphere's 90, times 2000 of 2200 inliers.
  EXPECT_NEAR(f->confidence, 60.0 / 90.0 * 2000.0 / 2200.0, 0.05);
}

TEST(PrimitiveFit, SphereWithoutNormals) {
  SampleMaker m(5);
  Samples s;
  test::add_sphere(s, m, V(0, 0, 0.1), 0.03, V::UnitZ(), M_PI / 2, 1500);
  s.normals.clear();
  const auto f = fit(PrimitiveKind::kSphere, s);
  ASSERT_TRUE(f);
  const auto& sphere = std::get<SphereModel>(f->model);
  EXPECT_LT((sphere.center - V(0, 0, 0.1)).norm(), 0.001);
  EXPECT_NEAR(sphere.radius, 0.03, 0.0005);
}

TEST(PrimitiveFit, TorusOuterSide) {
  SampleMaker m(6);
  Samples s;
  const V center(0.1, 0.2, 0.3), axis = V(0.1, 0.2, 1).normalized();
  test::add_torus(s, m, center, axis, 0.05, 0.012, -M_PI / 2, M_PI / 2, 3000);
  m.add_outliers(s, 150, center - V(0.07, 0.07, 0.02), center + V(0.07, 0.07, 0.02));
  const auto f = fit(PrimitiveKind::kTorus, s);
  ASSERT_TRUE(f);
  const auto& t = std::get<TorusModel>(f->model);
  EXPECT_NEAR(t.major_radius, 0.05, 0.0008);
  EXPECT_NEAR(t.minor_radius, 0.012, 0.0008);
  EXPECT_LT(angle_deg(t.axis, axis), 1.0);
  EXPECT_LT((t.center - center).norm(), 0.001);
  EXPECT_GT(f->confidence, 0.85);
}

TEST(PrimitiveFit, EdgeIsTheCreaseOfItsTwoFaces) {
  SampleMaker m(7);
  Samples s;
  // A box's top edge: the top face goes off along -y, the side face down along -z.
  const V point(0.1, 0.05, 0.2), direction = V::UnitX();
  test::add_edge_band(s, m, point, direction, V(0, -1, 0), V(0, 0, -1), 0.15, 0.025, 2000);
  const auto f = fit(PrimitiveKind::kLine, s);
  ASSERT_TRUE(f);
  const auto& line = std::get<LineModel>(f->model);
  EXPECT_LT(angle_deg(line.direction, direction), 0.5);
  EXPECT_LT(line_distance(line.center, point, direction), 0.0005);
  EXPECT_NEAR(line.center.x(), point.x(), 0.005);
  EXPECT_NEAR(line.length, 0.15, 0.005);
  EXPECT_GT(f->confidence, 0.95);
}

// Model selection (FitSettings::prefer_simpler): a curved fit is reported only when it describes
// its points better than the simpler surfaces do. Each case first shows the curved fitter does
// return a model on those points, so the check can fail.
std::optional<Fit> fit_with(PrimitiveKind kind, const Samples& s, bool prefer_simpler,
                            double max_radius = FitSettings{}.max_radius) {
  const std::vector<std::uint32_t> idx = s.indices();
  FitSettings settings;
  settings.prefer_simpler = prefer_simpler;
  settings.max_radius = max_radius;
  return fit_model(kind, SegmentPoints{s.xyz, s.normals, idx}, settings, 1);
}
std::optional<Fit> fit_without_selection(PrimitiveKind kind, const Samples& s) {
  return fit_with(kind, s, false);
}

TEST(PrimitiveFit, FlatPatchIsNotReportedAsSphereOrTorus) {
  SampleMaker m(11);
  Samples s;
  // A 12 x 8 cm patch of a table top, 0.5 mm noise, normals tilted a few degrees. With radii up
  // to 50 m the sphere and torus fitters find one (a large, flat one) on it.
  for (int i = 0; i < 1000; ++i)
    m.add(s, V(m.uniform(0, 0.12), m.uniform(0, 0.08), 0.7), V::UnitZ());
  for (PrimitiveKind kind : {PrimitiveKind::kSphere, PrimitiveKind::kTorus}) {
    SCOPED_TRACE(std::string(kind_name(kind)));
    ASSERT_TRUE(fit_with(kind, s, false, 50.0));
    EXPECT_FALSE(fit_with(kind, s, true, 50.0));
  }
  EXPECT_TRUE(fit(PrimitiveKind::kPlane, s));
}

TEST(PrimitiveFit, NearPlanarSpherePatchIsNotReportedAsTorus) {
  SampleMaker m(11);
  Samples s;
  // A 6 x 4 cm patch of a sphere of radius 1.5 m (0.2 mm from its tangent plane at the corners,
  // under the 0.5 mm noise): the torus fitter finds a torus on it; a plane or a sphere says as
  // much with fewer parameters.
  const V center(0, 0, -0.8);
  for (int i = 0; i < 2000; ++i) {
    const V d = V(m.uniform(-0.03, 0.03), m.uniform(-0.02, 0.02), 1.5).normalized();
    m.add(s, center + 1.5 * d, d);
  }
  const auto torus = fit_without_selection(PrimitiveKind::kTorus, s);
  ASSERT_TRUE(torus);
  const std::vector<std::uint32_t> idx = s.indices();
  EXPECT_FALSE(explains_better_than_simpler(
      PrimitiveKind::kTorus, *torus, SegmentPoints{s.xyz, s.normals, idx}, FitSettings{}, 1));
  EXPECT_FALSE(fit(PrimitiveKind::kTorus, s));
}

TEST(PrimitiveFit, CylinderPatchIsNotReportedAsTorus) {
  SampleMaker m(12);
  Samples s;
  // 400 points on 2 cm of a torus with a 0.5 m major radius: its centre circle 0.1 mm off
  // straight, under the 0.5 mm noise.
  for (int i = 0; i < 400; ++i) {
    const double phi = m.uniform(-0.02, 0.02), theta = m.uniform(-M_PI / 2, M_PI / 2);
    const V radial(std::cos(phi), std::sin(phi), 0);
    const V n = std::cos(theta) * radial + std::sin(theta) * V::UnitZ();
    m.add(s, V(-0.5, 0, 0) + 0.5 * radial + 0.04 * n, n);
  }
  ASSERT_TRUE(fit_without_selection(PrimitiveKind::kTorus, s));
  EXPECT_FALSE(fit(PrimitiveKind::kTorus, s));
  EXPECT_TRUE(fit(PrimitiveKind::kCylinder, s));  // and the cylinder beats the plane
}

TEST(PrimitiveFit, TrueTorusBeatsPlaneCylinderAndSphere) {
  SampleMaker m(13);
  Samples s;
  // A mug's handle-sized torus seen from one side: half the tube all round the axis.
  test::add_torus(s, m, V(0, 0, 0.1), V::UnitX(), 0.03, 0.006, -M_PI / 2, M_PI / 2, 2000);
  const auto f = fit(PrimitiveKind::kTorus, s);
  ASSERT_TRUE(f);
  EXPECT_NEAR(std::get<TorusModel>(f->model).major_radius, 0.03, 0.001);
}

// The bounds above bite: the same cylinder fitted as a sphere is far off any of them.
TEST(PrimitiveFit, WrongModelFitsBadly) {
  SampleMaker m(8);
  Samples s;
  test::add_cylinder(s, m, V::Zero(), V::UnitZ(), 0.04, 0.2, M_PI, 3000);
  const auto cylinder = fit(PrimitiveKind::kCylinder, s);
  const auto sphere = fit(PrimitiveKind::kSphere, s);
  ASSERT_TRUE(cylinder);
  EXPECT_GT(cylinder->confidence, 0.9);
  if (sphere) {
    EXPECT_LT(sphere->confidence, 0.5);
  }
}

TEST(PrimitiveFit, SameSeedSameFit) {
  SampleMaker m(9);
  Samples s;
  test::add_cylinder(s, m, V::Zero(), V::UnitY(), 0.03, 0.1, M_PI, 1000);
  const auto a = fit(PrimitiveKind::kCylinder, s, 5), b = fit(PrimitiveKind::kCylinder, s, 5);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(std::get<CylinderModel>(a->model).radius, std::get<CylinderModel>(b->model).radius);
  EXPECT_EQ(a->inliers, b->inliers);
}

// Segments no model can be fitted to give nothing or a finite fit, never a crash.
TEST(PrimitiveFit, HostileSegments) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<Samples> cases(6);
  cases[1].xyz = {Vec3f(0, 0, 0)};
  cases[2].xyz = {Vec3f(0, 0, 0), Vec3f(1, 0, 0)};
  cases[3].xyz.assign(200, Vec3f(0.5f, 0.5f, 0.5f));  // coincident
  cases[3].normals.assign(200, Vec3f(0, 0, 1));
  cases[4].xyz.assign(100, Vec3f(nan, 0, 0));
  cases[4].xyz.push_back(Vec3f(inf, 1, 1));
  for (int i = 0; i < 100; ++i) {  // collinear, NaN normals
    cases[5].xyz.push_back(Vec3f(0.001f * i, 0, 0));
    cases[5].normals.push_back(Vec3f(nan, nan, nan));
  }
  for (const Samples& s : cases) {
    const std::vector<std::uint32_t> idx = s.indices();
    for (PrimitiveKind kind :
         {PrimitiveKind::kPlane, PrimitiveKind::kCylinder, PrimitiveKind::kSphere,
          PrimitiveKind::kTorus, PrimitiveKind::kLine, PrimitiveKind::kSegment}) {
      const auto f = fit_model(kind, SegmentPoints{s.xyz, s.normals, idx}, FitSettings{}, 1);
      if (!f) continue;
      EXPECT_TRUE(std::isfinite(f->rms));
      EXPECT_GE(f->confidence, 0.0);
      EXPECT_LE(f->confidence, 1.0);
    }
  }
  // Indices past the cloud are skipped, not read.
  Samples s;
  s.xyz = {Vec3f(0, 0, 0)};
  const std::vector<std::uint32_t> idx = {0, 5, 1000000};
  EXPECT_FALSE(fit_plane(SegmentPoints{s.xyz, {}, idx}, FitSettings{}, 1));
}

TEST(PrimitiveFit, SettingsAreValidated) {
  FitSettings settings;
  settings.distance_threshold = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(settings.validate(), std::invalid_argument);
  settings = FitSettings{};
  settings.min_radius = 3;
  EXPECT_THROW(settings.validate(), std::invalid_argument);
  EXPECT_NO_THROW(FitSettings{}.validate());
}

}  // namespace
}  // namespace primlabel::primitives
