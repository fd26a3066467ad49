// The true primitives of synthetic scenes: every noise-free scan point of a curved or flat
// surface lies on its object's true primitive, and the counts say which ones the sensor saw.

#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/synth/generate.hpp"
#include "primlabel/synth/true_primitives.hpp"

namespace primlabel::synth {
namespace {

using primitives::PrimitiveKind;

Generated exact_scan(SceneKind scene, SensorKind sensor, std::uint64_t seed) {
  GenerateOptions options;
  options.scene = scene;
  options.sensor = sensor;
  options.seed = seed;
  options.noise_scale = 0;  // exact ranges: the points are on the surfaces
  return generate(options);
}

// The share of the points of each class on the objects that lie within 0.2 mm of one of their
// object's true primitives of that class (both torus classes share one torus). Torus-labeled
// points count on rings only: mug handles and bowl lips are torus-like at the label scale but
// not whole tori, and the list leaves them out.
std::map<std::uint32_t, double> share_on_truth(const Generated& scan,
                                               const std::vector<TruePrimitive>& truth) {
  const FloatField* object = scan.cloud.find_field("object");
  std::map<std::uint32_t, std::pair<std::size_t, std::size_t>> on;  // class -> (on, all)
  for (std::size_t i = 0; i < scan.cloud.size(); ++i) {
    const int owner = int(object->values[i]);
    const std::uint32_t label = scan.cloud.labels[i];
    if (owner < 0 || !is_finite(scan.cloud.xyz[i])) continue;
    const bool torus = label == class_id(PrimitiveClass::kTorusConvex) ||
                       label == class_id(PrimitiveClass::kTorusConcave);
    if (torus && scan.scene.objects[owner].shape->kind() != "torus") continue;
    double best = INFINITY;
    for (const TruePrimitive& t : truth) {
      const bool same_class =
          t.primitive.class_id == label ||
          (torus && t.primitive.class_id == class_id(PrimitiveClass::kTorusConvex));
      if (t.object == owner && same_class)
        best = std::min(best, distance_to(t.primitive.model, scan.cloud.xyz[i].cast<double>()));
    }
    auto& [n_on, n_all] = on[label];
    ++n_all;
    n_on += best <= 2e-4;
  }
  std::map<std::uint32_t, double> share;
  for (const auto& [label, counts] : on)
    share[label] = double(counts.first) / double(std::max<std::size_t>(counts.second, 1));
  return share;
}

TEST(TruePrimitives, EverySurfacePointLiesOnItsObjectsPrimitive) {
  for (SensorKind sensor : {SensorKind::kLms400, SensorKind::kKinect}) {
    const Generated scan = exact_scan(SceneKind::kPrimitives, sensor, 3);
    const std::vector<TruePrimitive> truth = true_primitives(scan.scene);
    const auto share = share_on_truth(scan, truth);
    // Planes (box faces, lids, the table), cylinders (cans, mugs), spheres (balls, bowls) and
    // tori: all of them are in the scene and all their points are on the truth. (Mug handles
    // are torus arcs the list leaves out, hence the torus tolerance.)
    for (PrimitiveClass c :
         {PrimitiveClass::kPlane, PrimitiveClass::kCylinderConvex, PrimitiveClass::kCylinderConcave,
          PrimitiveClass::kSphereConvex, PrimitiveClass::kSphereConcave}) {
      ASSERT_TRUE(share.count(class_id(c))) << name(c);
      EXPECT_GT(share.at(class_id(c)), 0.999) << name(c) << " " << sensor_name(sensor);
    }
    ASSERT_TRUE(share.count(class_id(PrimitiveClass::kTorusConvex)));
    EXPECT_GT(share.at(class_id(PrimitiveClass::kTorusConvex)), 0.6) << sensor_name(sensor);
  }
}

TEST(TruePrimitives, RandomTablesAreCoveredAndCountsSayWhatWasSeen) {
  for (std::uint64_t seed : {3000u, 3001u}) {
    const Generated scan = exact_scan(SceneKind::kTable, SensorKind::kLms400, seed);
    std::vector<TruePrimitive> truth = true_primitives(scan.scene);
    const auto share = share_on_truth(scan, truth);
    EXPECT_GT(share.at(class_id(PrimitiveClass::kPlane)), 0.999) << seed;
    count_points_on(truth, scan.cloud, 3e-4);
    // The table's top is the largest seen primitive, its bottom is seen only along the edge it
    // shares with the sides; every object in the scan has seen primitives (its edge and corner
    // points count for none).
    // A point counts as its own for one primitive at most, the nearest: the bottom, seen only
    // through the sides' points along its edges, has next to none of its own.
    std::size_t most = 0, table_top = 0, table_bottom = 0, top_own = 0, bottom_own = 0, own = 0;
    std::map<int, std::size_t> seen_per_object;
    for (const TruePrimitive& t : truth) {
      most = std::max(most, t.primitive.points);
      seen_per_object[t.object] += t.primitive.points;
      EXPECT_LE(t.own_points, t.primitive.points);
      own += t.own_points;
      const auto* plane = std::get_if<primitives::PlaneModel>(&t.primitive.model);
      if (t.object == 0 && plane && plane->normal.z() > 0.99)
        table_top = t.primitive.points, top_own = t.own_points;
      if (t.object == 0 && plane && plane->normal.z() < -0.99)
        table_bottom = t.primitive.points, bottom_own = t.own_points;
      EXPECT_EQ(t.primitive.confidence, 1.0);
    }
    EXPECT_EQ(table_top, most) << seed;
    EXPECT_LT(table_bottom, table_top / 100) << seed;
    EXPECT_GT(top_own, table_top * 99 / 100) << seed;
    EXPECT_LT(bottom_own, 10u) << seed;
    EXPECT_LE(own, scan.cloud.size()) << seed;
    const FloatField* object = scan.cloud.find_field("object");
    std::map<int, std::size_t> in_scan;
    for (float o : object->values) ++in_scan[int(o)];
    in_scan.erase(-1);
    ASSERT_GE(in_scan.size(), 5u);
    for (const auto& [o, n] : in_scan)
      if (n >= 100) EXPECT_GT(seen_per_object[o], n / 5) << "object " << o << ", seed " << seed;
  }
}

TEST(TruePrimitives, DistancesFollowEachModel) {
  using primitives::Vec3d;
  const primitives::CylinderModel can{Vec3d(0, 0, 0.1), Vec3d::UnitZ(), 0.05, 0.2};
  EXPECT_NEAR(distance_to(can, Vec3d(0.05, 0, 0.15)), 0, 1e-12);
  EXPECT_NEAR(distance_to(can, Vec3d(0.07, 0, 0.1)), 0.02, 1e-12);
  EXPECT_NEAR(distance_to(can, Vec3d(0.05, 0, 0.23)), 0.03, 1e-12);  // beyond its top
  primitives::PlaneModel face;
  face.extent_u = 0.2, face.extent_v = 0.1;
  EXPECT_NEAR(distance_to(face, Vec3d(0.05, 0.02, 0.01)), 0.01, 1e-12);
  EXPECT_NEAR(distance_to(face, Vec3d(0.13, 0, 0)), 0.03, 1e-12);  // beyond its edge
  const primitives::TorusModel ring{Vec3d::Zero(), Vec3d::UnitZ(), 0.1, 0.02};
  EXPECT_NEAR(distance_to(ring, Vec3d(0.12, 0, 0)), 0, 1e-12);
  EXPECT_NEAR(distance_to(ring, Vec3d(0.1, 0, 0.05)), 0.03, 1e-12);
  EXPECT_TRUE(std::isinf(distance_to(primitives::Model{}, Vec3d::Zero())));
}

}  // namespace
}  // namespace primlabel::synth
