// label_cloud's table-top objects (LabelingOptions::want_objects): only with tabletop_only; the
// same objects and per-point ids at 1 and 2 threads; through the voxel fan-out every input point
// gets its voxel's object id; with primitives each object lists the segments lying in it.

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>

#include "one_and_two_threads.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "random_label_model.hpp"
#include "tabletop_objects_scene.hpp"

namespace primlabel::pipeline {
namespace {

using tabletop::kNoObject;
using tabletop::TabletopObjects;

// Every described point a plane: the node bias of class 1 only.
LabelModel all_planes_model() {
  LabelModel model = testing::random_label_model("planes", "1");
  model.weights = crf::CrfModel::zeros({1, 2}, kFpfhSize);
  model.weights.node_weights(0, model.weights.node_feature_dim() - 1) = 1.0f;
  return model;
}

LabelingOptions object_options() {
  LabelingOptions options;
  options.tabletop_only = true;
  options.want_objects = true;
  options.want_primitives = true;
  options.primitives.segments.radius = 0.01f;
  return options;
}

void expect_same(const TabletopObjects& a, const TabletopObjects& b) {
  ASSERT_EQ(bool(a.table), bool(b.table));
  EXPECT_EQ(a.point_object, b.point_object);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  if (a.table) {
    EXPECT_EQ(a.table->points, b.table->points);
    EXPECT_EQ(a.table->plane, b.table->plane);
    EXPECT_EQ(a.table->primitive_ids, b.table->primitive_ids);
  }
  for (std::size_t k = 0; k < a.objects.size(); ++k) {
    EXPECT_EQ(a.objects[k].points, b.objects[k].points);
    EXPECT_EQ(a.objects[k].centroid, b.objects[k].centroid);
    EXPECT_EQ(a.objects[k].bounds_min, b.objects[k].bounds_min);
    EXPECT_EQ(a.objects[k].bounds_max, b.objects[k].bounds_max);
    EXPECT_EQ(a.objects[k].height, b.objects[k].height);
    EXPECT_EQ(a.objects[k].primitive_ids, b.objects[k].primitive_ids);
  }
}

TEST(PipelineObjects, RefusedWithoutTheTabletopStage) {
  const LabelModel model = all_planes_model();
  PointCloud cloud = testing::objects_scene(0.01f).cloud;
  LabelingOptions options = object_options();
  options.tabletop_only = false;
  try {
    label_cloud(model, cloud, options);
    FAIL() << "want_objects without tabletop_only was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tabletop_only"), std::string::npos) << e.what();
  }
  options = LabelingOptions{};
  options.tabletop_only = true;
  EXPECT_FALSE(label_cloud(model, cloud, options).objects);  // not asked for
}

TEST(PipelineObjects, SameObjectsAtOneAndTwoThreadsEachWithItsPrimitive) {
  const LabelModel model = all_planes_model();
  const testing::ObjectsScene scene = testing::objects_scene(0.005f, 0.02f);
  const auto [a, b] = testing::label_with_one_and_two_threads(model, scene.cloud, object_options());
  ASSERT_TRUE(a.objects && b.objects && a.primitives);
  expect_same(*a.objects, *b.objects);
  const TabletopObjects& objects = *a.objects;
  ASSERT_TRUE(objects.table);
  ASSERT_EQ(objects.objects.size(), 3u);
  // All plane-labelled, each object one connected segment, the table another.
  EXPECT_EQ(objects.table->primitive_ids.size(), 1u);
  for (const tabletop::TabletopObject& object : objects.objects) {
    ASSERT_EQ(object.primitive_ids.size(), 1u) << object.id;
    const primitives::Primitive& p = a.primitives->primitives[object.primitive_ids[0]];
    EXPECT_GE(p.bounds_min.z(), object.bounds_min.z() - 1e-6);
    EXPECT_LE(p.bounds_max.z(), object.bounds_max.z() + 1e-6);
    EXPECT_GE(2 * p.points, object.points);
  }
  // Only the table and the objects are labelled.
  for (std::size_t i = 0; i < scene.cloud.size(); ++i)
    if (objects.point_object[i] == kNoObject) EXPECT_EQ(a.labels[i], 0u) << i;
}

TEST(PipelineObjects, VoxelFanOutGivesEveryPointItsVoxelsObject) {
  const LabelModel model = all_planes_model();
  const testing::ObjectsScene scene = testing::objects_scene(0.004f);
  PointCloud cloud = scene.cloud;
  LabelingOptions options = object_options();
  options.voxel_size = 0.01f;
  options.primitives.segments.radius = 0.0f;
  const LabelingResult result = label_cloud(model, cloud, options, RunContext{2});
  ASSERT_TRUE(result.objects);
  const TabletopObjects& objects = *result.objects;
  ASSERT_EQ(objects.point_object.size(), scene.cloud.size());
  ASSERT_EQ(objects.objects.size(), 3u);
  // Each true object's points (above the table's band) all carry one object id, a different
  // one per object, and the object's counts and bounds are over the input points.
  std::set<std::uint32_t> ids;
  for (std::uint32_t part = 1; part <= 3; ++part) {
    std::set<std::uint32_t> seen;
    std::size_t points = 0;
    for (std::size_t i = 0; i < scene.cloud.size(); ++i)
      if (scene.object[i] == part && scene.cloud.xyz[i].z() > 0.015f) {
        seen.insert(objects.point_object[i]);
        ++points;
      }
    ASSERT_EQ(seen.size(), 1u) << part;
    const std::uint32_t id = *seen.begin();
    ASSERT_GE(id, 1u);
    ids.insert(id);
    EXPECT_GE(objects.objects[id - 1].points, points);
    EXPECT_NEAR(objects.objects[id - 1].bounds_max.z(), scene.hi[part].z(), 1e-4);
  }
  EXPECT_EQ(ids.size(), 3u);
  std::size_t table = 0;
  for (std::uint32_t id : objects.point_object) table += id == tabletop::kTableObject;
  EXPECT_EQ(objects.table->points, table);
  EXPECT_GT(table, scene.cloud.size() / 2);
}

}  // namespace
}  // namespace primlabel::pipeline
