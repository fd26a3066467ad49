// Shapes and ground truth: analytic ray hits land where geometry says, and labels at scale r
// follow the documented rules (box corners are corners, edges edges, face centres planes, ...).

#include <gtest/gtest.h>

#include "primlabel/synth/ground_truth.hpp"
#include "primlabel/synth/scene.hpp"
#include "primlabel/synth/shapes.hpp"

namespace primlabel::synth {
namespace {

constexpr double kR = 0.025;  // label radius

Ray down_at(double x, double y) { return Ray{Vec3d(x, y, 1.0), Vec3d(0, 0, -1)}; }
Ray along_x(double y, double z) { return Ray{Vec3d(-1.0, y, z), Vec3d(1, 0, 0)}; }

SurfaceHit hit_of(const Shape& shape, const Ray& ray) {
  SurfaceHit hit;
  EXPECT_TRUE(shape.intersect(ray, 1e-9, 10.0, hit));
  return hit;
}

TEST(Shapes, BoxHitsTheFaceTheRayEnters) {
  const BoxShape box(Vec3d(0.2, 0.1, 0.1));
  SurfaceHit hit = hit_of(box, down_at(0.05, 0.01));
  EXPECT_NEAR(hit.t, 0.9, 1e-12);
  EXPECT_EQ(hit.part, 5);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-12);
  hit = hit_of(box, along_x(0.0, 0.05));
  EXPECT_NEAR(hit.t, 0.9, 1e-12);
  EXPECT_EQ(hit.part, 0);
  EXPECT_NEAR(hit.normal.x(), -1.0, 1e-12);
  SurfaceHit miss;
  EXPECT_FALSE(box.intersect(down_at(0.2, 0.0), 1e-9, 10.0, miss));
  EXPECT_FALSE(box.intersect(down_at(0.05, 0.01), 1e-9, 0.5, miss));  // beyond t_max
}

TEST(Shapes, CanSideAndLid) {
  const CanShape can(0.04, 0.12);
  SurfaceHit hit = hit_of(can, along_x(0.0, 0.06));
  EXPECT_NEAR(hit.t, 1.0 - 0.04, 1e-12);
  EXPECT_EQ(can.surface_class(hit.part, Vec3d(-0.04, 0, 0.06)), PrimitiveClass::kCylinderConvex);
  hit = hit_of(can, down_at(0.01, 0.0));
  EXPECT_NEAR(hit.t, 1.0 - 0.12, 1e-12);
  EXPECT_EQ(hit.part, 1);
}

TEST(Shapes, LyingCanSideAndCaps) {
  const LyingCanShape can(0.04, 0.16);  // axis x, on the table along y = 0
  SurfaceHit hit = hit_of(can, down_at(0.03, 0.0));
  EXPECT_NEAR(hit.t, 1.0 - 0.08, 1e-12);  // the top of the side
  EXPECT_EQ(hit.part, 0);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-12);
  EXPECT_EQ(can.surface_class(0, Vec3d()), PrimitiveClass::kCylinderConvex);
  hit = hit_of(can, along_x(0.0, 0.04));  // from -x: the -x cap
  EXPECT_NEAR(hit.t, 1.0 - 0.08, 1e-12);
  EXPECT_EQ(hit.part, 2);
  EXPECT_NEAR(hit.normal.x(), -1.0, 1e-12);
  EXPECT_EQ(can.surface_class(2, Vec3d()), PrimitiveClass::kPlane);
  EXPECT_NEAR(can.distance_outside(Vec3d(0.0, 0.0, 0.1)), 0.02, 1e-12);
  EXPECT_NEAR(can.distance_outside(Vec3d(0.1, 0.0, 0.04)), 0.02, 1e-12);
  // Both cap circles are convex edges of the side and their cap.
  int edges_near_plus_cap = 0;
  for (const Feature& f : can.features())
    edges_near_plus_cap += f.distance(Vec3d(0.08, 0.0, 0.0)) < 1e-12 && (f.parts >> 1 & 1u);
  EXPECT_EQ(edges_near_plus_cap, 1);
}

TEST(Shapes, MugFloorLipWallsAndHandle) {
  const MugShape::Handle handle{0.028, 0.006, 0.055, 0.01};
  const MugShape mug(0.042, 0.10, 0.005, 0.008, handle);
  SurfaceHit hit = hit_of(mug, down_at(0.0, 0.0));  // straight into the cavity
  EXPECT_NEAR(1.0 - hit.t, 0.008, 1e-12);
  EXPECT_EQ(hit.part, 3);
  hit = hit_of(mug, down_at(0.0, 0.0395));  // onto the lip
  EXPECT_NEAR(1.0 - hit.t, 0.10, 1e-12);
  EXPECT_EQ(hit.part, 2);
  hit = hit_of(mug, along_x(0.0, 0.03));  // outer wall, far from the handle (it is at +x)
  EXPECT_NEAR(hit.t, 1.0 - 0.042, 1e-12);
  EXPECT_EQ(hit.part, 0);
  // From +x at the handle's height the ring's outer side comes first.
  const Ray from_right{Vec3d(1.0, 0.0, 0.055), Vec3d(-1, 0, 0)};
  hit = hit_of(mug, from_right);
  EXPECT_EQ(hit.part, 5);
  EXPECT_NEAR(1.0 - hit.t, 0.042 + 0.01 + 0.028 + 0.006, 1e-6);
  // Through the cavity at a slant: the inner wall.
  const Ray slant{Vec3d(-0.02, 0.0, 0.2), Vec3d(1.0, 0.0, -2.0).normalized()};
  hit = hit_of(mug, slant);
  EXPECT_EQ(hit.part, 1);
  EXPECT_EQ(mug.surface_class(1, Vec3d::Zero()), PrimitiveClass::kCylinderConcave);
}

TEST(Shapes, BowlInsideIsConcaveOutsideConvex) {
  const BowlShape bowl(0.08, 0.0);
  SurfaceHit hit = hit_of(bowl, down_at(0.0, 0.0));
  EXPECT_EQ(hit.part, 1);
  EXPECT_EQ(bowl.surface_class(hit.part, Vec3d::Zero()), PrimitiveClass::kSphereConcave);
  EXPECT_GT(1.0 - hit.t, 0.0);  // the inner bottom is above the table
  EXPECT_LT(1.0 - hit.t, bowl.rim_height());
  hit = hit_of(bowl, along_x(0.0, 0.03));
  EXPECT_EQ(hit.part, 0);
  EXPECT_EQ(bowl.surface_class(hit.part, Vec3d::Zero()), PrimitiveClass::kSphereConvex);
}

TEST(Shapes, BallAndTorus) {
  const BallShape ball(0.05);
  EXPECT_NEAR(1.0 - hit_of(ball, down_at(0, 0)).t, 0.1, 1e-12);

  const TorusShape torus(0.05, 0.02);
  SurfaceHit hit = hit_of(torus, down_at(0.05, 0.0));
  EXPECT_NEAR(1.0 - hit.t, 0.04, 1e-7);  // top of the tube
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-6);
  SurfaceHit miss;
  EXPECT_FALSE(torus.intersect(down_at(0.0, 0.0), 1e-9, 10.0, miss));  // through the hole
  hit = hit_of(torus, down_at(0.065, 0.0));
  EXPECT_EQ(torus.surface_class(0, Vec3d(0.065, 0, 0)), PrimitiveClass::kTorusConvex);
  EXPECT_EQ(torus.surface_class(0, Vec3d(0.04, 0, 0)), PrimitiveClass::kTorusConcave);
}

TEST(Shapes, FeatureDistances) {
  const Feature segment =
      Feature::segment(Feature::Kind::kConvexEdge, Vec3d(0, 0, 0), Vec3d(1, 0, 0));
  EXPECT_NEAR(segment.distance(Vec3d(0.5, 0.3, 0.4)), 0.5, 1e-12);
  EXPECT_NEAR(segment.distance(Vec3d(-0.3, 0.4, 0)), 0.5, 1e-12);  // beyond the end
  const Feature circle = Feature::circle(Feature::Kind::kRim, Vec3d(0, 0, 1), Vec3d::UnitZ(), 0.5);
  EXPECT_NEAR(circle.distance(Vec3d(0.8, 0, 1.4)), 0.5, 1e-12);
}

// A table with one box (0.2 x 0.16 x 0.1) at the origin and one mug at (0.3, 0).
class GroundTruth : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = make_scene(SceneKind::kEmptyTable, 1);
    scene_.objects.emplace_back(std::make_shared<BoxShape>(Vec3d(0.2, 0.16, 0.1)),
                                Eigen::Isometry3d::Identity(), 0xFF0000, true);
    Eigen::Isometry3d mug_pose = Eigen::Isometry3d::Identity();
    mug_pose.translate(Vec3d(0.3, 0.0, 0.0));
    scene_.objects.emplace_back(
        std::make_shared<MugShape>(0.042, 0.10, 0.005, 0.008, MugShape::Handle{}), mug_pose,
        0xFFFFFF, true);
  }
  PrimitiveClass box(int part, double x, double y, double z) {
    return ground_truth(scene_, 1, part, Vec3d(x, y, z), kR);
  }
  PrimitiveClass table(double x, double y) {
    return ground_truth(scene_, 0, 5, Vec3d(x, y, 0), kR);
  }
  PrimitiveClass mug(int part, double x, double y, double z) {
    return ground_truth(scene_, 2, part, Vec3d(0.3 + x, y, z), kR);
  }
  Scene scene_;
};

TEST_F(GroundTruth, BoxFacesEdgesAndCorners) {
  const int top = 5, front = 2;                                               // +z and -y faces
  EXPECT_EQ(box(top, 0.0, 0.0, 0.1), PrimitiveClass::kPlane);                 // face centre
  EXPECT_EQ(box(top, 0.0, -0.08 + 0.01, 0.1), PrimitiveClass::kEdgeConvex);   // 1 cm from an edge
  EXPECT_EQ(box(top, 0.0, -0.08 + 0.024, 0.1), PrimitiveClass::kEdgeConvex);  // just inside r
  EXPECT_EQ(box(top, 0.0, -0.08 + 0.026, 0.1), PrimitiveClass::kPlane);       // just outside r
  EXPECT_EQ(box(top, -0.1 + 0.01, -0.08 + 0.01, 0.1), PrimitiveClass::kCorner);
  EXPECT_EQ(box(top, -0.1 + 0.02, -0.08 + 0.02, 0.1), PrimitiveClass::kCorner);
  EXPECT_EQ(box(front, 0.0, -0.08, 0.05), PrimitiveClass::kPlane);
  EXPECT_EQ(box(front, -0.1 + 0.01, -0.08, 0.05), PrimitiveClass::kEdgeConvex);  // vertical edge
  EXPECT_EQ(box(front, 0.0, -0.08, 0.01), PrimitiveClass::kEdgeConcave);     // stands on the table
  EXPECT_EQ(box(front, -0.1 + 0.01, -0.08, 0.01), PrimitiveClass::kCorner);  // edge + contact
}

TEST_F(GroundTruth, TableAroundObjectsIsAConcaveCrease) {
  EXPECT_EQ(table(0.0, -0.08 - 0.01), PrimitiveClass::kEdgeConcave);
  EXPECT_EQ(table(0.0, -0.08 - 0.03), PrimitiveClass::kPlane);
  EXPECT_EQ(table(0.3 - 0.042 - 0.02, 0.0), PrimitiveClass::kEdgeConcave);  // beside the mug
  EXPECT_EQ(table(-0.5, 0.2), PrimitiveClass::kPlane);
  // The table's front edge (y = -0.4) is a convex edge.
  EXPECT_EQ(table(0.0, -0.4 + 0.01), PrimitiveClass::kEdgeConvex);
}

TEST_F(GroundTruth, MugWallsRimAndFloor) {
  const int outer = 0, inner = 1, floor = 3;
  EXPECT_EQ(mug(outer, -0.042, 0.0, 0.05), PrimitiveClass::kCylinderConvex);
  EXPECT_EQ(mug(outer, -0.042, 0.0, 0.09), PrimitiveClass::kTorusConvex);  // near the rim
  EXPECT_EQ(mug(inner, -0.037, 0.0, 0.05), PrimitiveClass::kCylinderConcave);
  EXPECT_EQ(mug(inner, -0.037, 0.0, 0.09), PrimitiveClass::kTorusConvex);
  EXPECT_EQ(mug(floor, 0.0, 0.0, 0.008), PrimitiveClass::kPlane);
  // Inside, near the wall: a concave crease, not a contact with the table through the wall.
  EXPECT_EQ(mug(floor, -0.03, 0.0, 0.008), PrimitiveClass::kEdgeConcave);
  EXPECT_EQ(mug(outer, -0.042, 0.0, 0.01), PrimitiveClass::kEdgeConcave);  // foot on the table
}

TEST(SceneGeneration, ObjectsStandOnTheTableApart) {
  for (std::uint64_t seed : {1, 2, 3, 4, 5}) {
    const Scene scene = make_scene(SceneKind::kTable, seed);
    const TableSceneOptions defaults;
    ASSERT_GE(int(scene.objects.size()) - 1, defaults.min_objects - 2) << seed;
    ASSERT_LE(int(scene.objects.size()) - 1, defaults.max_objects) << seed;
    for (std::size_t i = 1; i < scene.objects.size(); ++i) {
      const SceneObject& a = scene.objects[i];
      const Vec3d pa = a.world_from_local.translation();
      EXPECT_EQ(pa.z(), 0.0);
      EXPECT_LE(std::abs(pa.x()) + a.shape->footprint_radius(), 0.5 * scene.table_size.x());
      EXPECT_LE(std::abs(pa.y()) + a.shape->footprint_radius(), 0.5 * scene.table_size.y());
      for (std::size_t j = 1; j < i; ++j) {
        const SceneObject& b = scene.objects[j];
        const Vec3d pb = b.world_from_local.translation();
        EXPECT_GE(
            (pa - pb).head<2>().norm(),
            a.shape->footprint_radius() + b.shape->footprint_radius() + defaults.min_gap - 1e-9);
      }
    }
  }
  EXPECT_EQ(describe_objects(make_scene(SceneKind::kPrimitives, 1)), "box,can,mug,bowl,ball,torus");
}

}  // namespace
}  // namespace primlabel::synth
