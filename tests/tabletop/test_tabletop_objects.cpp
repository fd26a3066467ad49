// Table-top objects as instances (tabletop_objects.hpp, objects_json.hpp): on a synthetic table
// with two boxes and a can, three objects with their true bounds and heights, and with the true
// labels fitted as primitives, each object holding exactly its own primitive segments.

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>

#include "primlabel/primitives/fit_primitives.hpp"
#include "primlabel/tabletop/objects_json.hpp"
#include "primlabel/tabletop/tabletop_objects.hpp"
#include "tabletop_objects_scene.hpp"

namespace primlabel::tabletop {
namespace {

using testing::objects_scene;
using testing::ObjectsScene;

// Our object id of each true part (the id most of its points carry).
std::map<std::uint32_t, std::uint32_t> part_to_object(const ObjectsScene& scene,
                                                      const TabletopObjects& objects) {
  std::map<std::uint32_t, std::map<std::uint32_t, std::size_t>> votes;
  for (std::size_t i = 0; i < scene.object.size(); ++i)
    ++votes[scene.object[i]][objects.point_object[i]];
  std::map<std::uint32_t, std::uint32_t> out;
  for (const auto& [part, counts] : votes)
    out[part] = std::max_element(counts.begin(), counts.end(), [](auto& a, auto& b) {
                  return a.second < b.second;
                })->first;
  return out;
}

TabletopObjects segmented(const ObjectsScene& scene) {
  const TabletopResult result = segment_tabletop(scene.cloud, TabletopOptions{});
  EXPECT_TRUE(result.ok()) << result.message;
  TabletopObjects objects = object_ids(result, scene.cloud.size());
  describe_objects(scene.cloud.xyz, objects);
  return objects;
}

TEST(TabletopObjects, TwoBoxesAndACanWithTheirBoundsAndHeights) {
  const ObjectsScene scene = objects_scene(0.005f);
  const TabletopObjects objects = segmented(scene);
  ASSERT_TRUE(objects.table);
  EXPECT_NEAR(std::abs(objects.table->plane[2]), 1.0f, 1e-3f);
  EXPECT_NEAR(objects.table->plane[3], 0.0f, 1e-3f);
  EXPECT_GE(objects.table->hull.size(), 4u);
  ASSERT_EQ(objects.objects.size(), 3u);
  const auto ids = part_to_object(scene, objects);
  EXPECT_EQ(ids.at(0), kTableObject);
  std::set<std::uint32_t> distinct;
  std::size_t object_points = 0;
  for (int part = 1; part <= 3; ++part) {
    const std::uint32_t id = ids.at(part);
    ASSERT_GE(id, 1u);
    ASSERT_LE(id, 3u);
    distinct.insert(id);
    const TabletopObject& object = objects.objects[id - 1];
    EXPECT_EQ(object.id, id);
    object_points += object.points;
    // The lowest rows lie in the table's band and go to the table: z from about 1 cm.
    EXPECT_NEAR(object.bounds_min.z(), scene.lo[part].z(), 0.012) << part;
    for (int axis = 0; axis < 2; ++axis) {
      EXPECT_NEAR(object.bounds_min[axis], scene.lo[part][axis], 1e-4) << part << " " << axis;
      EXPECT_NEAR(object.bounds_max[axis], scene.hi[part][axis], 1e-4) << part << " " << axis;
    }
    EXPECT_NEAR(object.bounds_max.z(), scene.hi[part].z(), 1e-4) << part;
    EXPECT_NEAR(object.height, scene.hi[part].z(), 1e-3) << part;
    const Eigen::Vector3d middle = 0.5 * (scene.lo[part] + scene.hi[part]);
    EXPECT_NEAR(object.centroid.x(), middle.x(), 0.01) << part;
    EXPECT_NEAR(object.centroid.y(), middle.y(), 0.01) << part;
  }
  EXPECT_EQ(distinct.size(), 3u);
  // Largest first, and the counts are those of the ids.
  for (std::size_t k = 1; k < objects.objects.size(); ++k)
    EXPECT_GE(objects.objects[k - 1].points, objects.objects[k].points);
  const auto with = [&](std::uint32_t id) {
    return std::size_t(std::count(objects.point_object.begin(), objects.point_object.end(), id));
  };
  EXPECT_EQ(objects.table->points, with(kTableObject));
  EXPECT_EQ(object_points, with(1) + with(2) + with(3));
  EXPECT_EQ(objects.point_object.size(), scene.cloud.size());
}

TEST(TabletopObjects, EachObjectHoldsItsOwnPrimitives) {
  // Lifted 2 cm so the true labels' segments do not run into the table.
  const ObjectsScene scene = objects_scene(0.005f, 0.02f);
  TabletopObjects objects = segmented(scene);
  ASSERT_EQ(objects.objects.size(), 3u);
  primitives::PrimitiveOptions options;
  options.segments.radius = 0.01f;
  const primitives::PrimitiveSet fitted =
      primitives::fit_primitives(scene.cloud.xyz, scene.cloud.normals, scene.labels, options);
  std::vector<std::size_t> sizes;
  for (const primitives::Primitive& p : fitted.primitives) sizes.push_back(p.points);
  assign_primitives(fitted.point_segment, sizes, objects);
  const auto ids = part_to_object(scene, objects);

  ASSERT_EQ(objects.table->primitive_ids.size(), 1u);
  const primitives::Primitive& table = fitted.primitives[objects.table->primitive_ids[0]];
  EXPECT_EQ(table.kind(), primitives::PrimitiveKind::kPlane);
  for (int part = 1; part <= 2; ++part) {  // a box: its faces are one plane-class segment
    const TabletopObject& box = objects.objects[ids.at(part) - 1];
    ASSERT_EQ(box.primitive_ids.size(), 1u) << part;
    EXPECT_EQ(fitted.primitives[box.primitive_ids[0]].class_id, class_id(PrimitiveClass::kPlane));
  }
  const TabletopObject& can = objects.objects[ids.at(3) - 1];
  ASSERT_EQ(can.primitive_ids.size(), 2u);  // side and lid
  std::size_t cylinders = 0;
  for (std::uint32_t s : can.primitive_ids) {
    const auto* cylinder = std::get_if<primitives::CylinderModel>(&fitted.primitives[s].model);
    if (!cylinder) continue;
    ++cylinders;
    EXPECT_NEAR(cylinder->radius, ObjectsScene::kCanRadius, 0.002);
  }
  EXPECT_EQ(cylinders, 1u);
  // Every segment is in exactly one place.
  std::set<std::uint32_t> all(objects.table->primitive_ids.begin(),
                              objects.table->primitive_ids.end());
  std::size_t listed = objects.table->primitive_ids.size();
  for (const TabletopObject& o : objects.objects) {
    all.insert(o.primitive_ids.begin(), o.primitive_ids.end());
    listed += o.primitive_ids.size();
  }
  EXPECT_EQ(all.size(), listed);
  EXPECT_EQ(listed, fitted.primitives.size());
}

TEST(TabletopObjects, APrimitiveWithoutAMajorityBelongsToNoObject) {
  TabletopObjects objects;
  objects.table = TabletopTable{};
  objects.objects.resize(2);
  objects.objects[0].id = 1;
  objects.objects[1].id = 2;
  // Segment 0: 2 of 4 points in object 1 (no majority); segment 1: 3 of 4 in object 2.
  objects.point_object = {1, 1, 2, kNoObject, 2, 2, 2, 0, 0};
  const std::vector<std::uint32_t> segment = {0, 0, 0, 0, 1, 1, 1, 1, 0xFFFFFFFFu};
  const std::vector<std::size_t> sizes = {4, 4};
  assign_primitives(segment, sizes, objects);
  EXPECT_TRUE(objects.objects[0].primitive_ids.empty());
  EXPECT_EQ(objects.objects[1].primitive_ids, std::vector<std::uint32_t>{1});
  EXPECT_TRUE(objects.table->primitive_ids.empty());
  EXPECT_THROW(assign_primitives(std::vector<std::uint32_t>{0}, sizes, objects),
               std::invalid_argument);
  const std::vector<std::uint32_t> out_of_range = {0, 0, 0, 0, 1, 1, 1, 7, 0};
  EXPECT_THROW(assign_primitives(out_of_range, sizes, objects), std::invalid_argument);
}

TEST(TabletopObjects, NoTableGivesNoObjectsAndSaysWhy) {
  PointCloud empty;
  const TabletopObjects objects = object_ids(segment_tabletop(empty, TabletopOptions{}), 0);
  EXPECT_FALSE(objects.table);
  EXPECT_FALSE(objects.message.empty());
  EXPECT_TRUE(objects.objects.empty());
  const TabletopObjects read = parse_objects_json(objects_json(objects));
  EXPECT_FALSE(read.table);
  EXPECT_EQ(read.message, objects.message);
}

TEST(TabletopObjects, JsonRoundTrips) {
  const ObjectsScene scene = objects_scene(0.005f);
  TabletopObjects objects = segmented(scene);
  objects.objects[1].primitive_ids = {3, 5};
  objects.table->primitive_ids = {0};
  const TabletopObjects read = parse_objects_json(objects_json(objects));
  ASSERT_TRUE(read.table);
  EXPECT_EQ(read.table->points, objects.table->points);
  EXPECT_TRUE(read.table->plane.isApprox(objects.table->plane, 1e-6f));
  ASSERT_EQ(read.table->hull.size(), objects.table->hull.size());
  EXPECT_EQ(read.table->primitive_ids, objects.table->primitive_ids);
  ASSERT_EQ(read.objects.size(), objects.objects.size());
  for (std::size_t k = 0; k < read.objects.size(); ++k) {
    const TabletopObject &a = read.objects[k], &b = objects.objects[k];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.points, b.points);
    EXPECT_LT((a.centroid - b.centroid).norm(), 1e-6);
    EXPECT_LT((a.bounds_min - b.bounds_min).norm(), 1e-6);
    EXPECT_LT((a.bounds_max - b.bounds_max).norm(), 1e-6);
    EXPECT_NEAR(a.height, b.height, 1e-6);
    EXPECT_EQ(a.primitive_ids, b.primitive_ids);
  }
  EXPECT_THROW(parse_objects_json("{\"objects\": []}"), std::invalid_argument);
  EXPECT_THROW(parse_objects_json("{\"table\": null, \"objects\": [{\"id\": 2}]}"),
               std::invalid_argument);
  EXPECT_THROW(parse_objects_json("not json"), std::invalid_argument);
}

// The stage orders its clusters by voxels; the answer counts input points, and a near object's
// voxel holds more of them. Objects come largest first by those points, ids renumbered to match.
TEST(TabletopObjects, ObjectsAreLargestFirstByTheirPointsAndIdsFollow) {
  TabletopObjects objects;
  objects.table = TabletopTable{};
  objects.table->plane = Eigen::Vector4f(0, 0, 1, 0);
  objects.objects.resize(3);
  for (std::uint32_t k = 0; k < 3; ++k) objects.objects[k].id = k + 1;
  // Object 1 (the stage's largest by voxels) has 2 points, object 2 has 5, object 3 has 2.
  objects.point_object = {1, 2, 2, kTableObject, 2, 3, 2, 1, kNoObject, 2, 3};
  std::vector<Vec3f> xyz;
  for (std::size_t i = 0; i < objects.point_object.size(); ++i) xyz.emplace_back(float(i), 0, 0.1f);
  describe_objects(xyz, objects);
  ASSERT_EQ(objects.objects.size(), 3u);
  EXPECT_EQ(objects.objects[0].points, 5u);
  EXPECT_EQ(objects.objects[1].points, 2u);
  EXPECT_EQ(objects.objects[2].points, 2u);
  for (std::uint32_t k = 0; k < 3; ++k) EXPECT_EQ(objects.objects[k].id, k + 1);
  // Ties keep their order: the old object 1 before the old object 3.
  EXPECT_EQ(objects.point_object,
            (std::vector<std::uint32_t>{2, 1, 1, kTableObject, 1, 3, 1, 2, kNoObject, 1, 3}));
  EXPECT_DOUBLE_EQ(objects.objects[0].centroid.x(), (1 + 2 + 4 + 6 + 9) / 5.0);
}

}  // namespace
}  // namespace primlabel::tabletop
