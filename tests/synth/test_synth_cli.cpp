// primlabel-synth as a user runs it: outputs, scene sets, exit codes and one-line errors.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/primitives/primitives_json.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using Result = test::CommandResult;

Result run(const std::string& arguments) {
  return test::run_command(test::binary("primlabel-synth") + " " + arguments);
}

TEST(SynthCli, ListsTheClassesAsAClassMap) {
  const Result r = run("--list-classes");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, ClassMap::taxonomy().to_text());
  EXPECT_NE(r.output.find("6 corner\n"), std::string::npos);
}

TEST(SynthCli, WritesALabeledScene) {
  test::TempDir dir;
  const std::string out = dir.file("scene.pcd");
  const Result r = run("--scene table --sensor lms400 --seed 7 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("wrote " + out), std::string::npos);
  const PointCloud cloud = read_pcd(out);
  ASSERT_TRUE(cloud.has_labels());
  EXPECT_GT(cloud.size(), 50000u);
  const CloudTags tags = read_cloud_tags(out);
  EXPECT_EQ(tags.at("label_radius"), "0.025");
  EXPECT_EQ(tags.at("sensor"), "lms400");
  EXPECT_EQ(tags.at("seed"), "7");
  for (std::uint32_t label : cloud.labels) ASSERT_LT(label, kPrimitiveClassCount);
}

// The crowded table for the table-top stage, its instances in `label` as mOSD writes them.
TEST(SynthCli, ClutterSceneWithSegmentLabels) {
  test::TempDir dir;
  const std::string out = dir.file("clutter.pcd");
  const Result r = run("--scene clutter --sensor kinect --seed 8 --segment-labels -q -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PointCloud cloud = read_pcd(out);
  ASSERT_TRUE(cloud.has_labels());
  const FloatField* object = cloud.find_field("object");
  ASSERT_NE(object, nullptr);
  std::map<std::uint32_t, std::size_t> points;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const std::uint32_t label = cloud.labels[i];
    if (!is_finite(cloud.xyz[i])) {
      ASSERT_EQ(label, 0u) << i;
      continue;
    }
    const int k = static_cast<int>(object->values[i]);
    const bool table_side = k == 0 && cloud.xyz[i].z() < -0.015f;  // not the supporting top
    ASSERT_EQ(label, table_side ? 0u : k == 0 ? 1u : 10u * std::uint32_t(k + 1)) << i;
    ++points[label];
  }
  // Seed 8: the table and at least 8 seen objects, more than 10 when stacked boxes count.
  EXPECT_GT(points[1], 50000u);
  EXPECT_GT(points[0], 1000u) << "the slab's front face is seen";
  EXPECT_GE(points.size() - points.count(0), 1u + 8u);
  const CloudTags tags = read_cloud_tags(out);
  EXPECT_EQ(tags.at("scene"), "clutter");
  EXPECT_NE(tags.at("labels").find("segments"), std::string::npos);
}

// The crowded scene's instances: every object, leaning and stacked ones included, its own label.
TEST(SynthCli, CrowdedSceneWithSegmentLabels) {
  test::TempDir dir;
  const std::string out = dir.file("crowded.pcd");
  const Result r = run("--scene crowded --sensor kinect --seed 3 --segment-labels -q -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PointCloud cloud = read_pcd(out);
  const FloatField* object = cloud.find_field("object");
  ASSERT_NE(object, nullptr);
  std::set<std::uint32_t> labels;
  int objects = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!is_finite(cloud.xyz[i])) continue;
    const int k = static_cast<int>(object->values[i]);
    objects = std::max(objects, k);
    if (k > 0) ASSERT_EQ(cloud.labels[i], 10u * std::uint32_t(k + 1)) << i;
    labels.insert(cloud.labels[i]);
  }
  EXPECT_TRUE(labels.count(1u)) << "the table top";
  EXPECT_GE(objects, 8);
  EXPECT_LE(objects, 14);
  for (int k = 1; k <= objects; ++k) EXPECT_TRUE(labels.count(10u * (k + 1))) << k;
  EXPECT_EQ(read_cloud_tags(out).at("scene"), "crowded");
}

TEST(SynthCli, KinectPrimitivesWithRadiusToPly) {
  test::TempDir dir;
  const std::string out = dir.file("prims.ply");
  const Result r = run("--scene primitives --sensor kinect --seed 3 --radius 0.03 -q -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");
  const CloudTags tags = read_cloud_tags(out);
  EXPECT_EQ(tags.at("label_radius"), "0.03");
  EXPECT_EQ(tags.at("objects"), "box,can,mug,bowl,ball,torus");
  const PointCloud cloud = load_labeled_cloud(out);
  EXPECT_EQ(cloud.size(), 640u * 480u);
}

TEST(SynthCli, WritesASceneSetWithManifest) {
  test::TempDir dir;
  const std::string set_dir = dir.file("val");
  const Result r = run("--set val --count 2 --out-dir " + set_dir + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string file : {"val_0000.pcd", "val_0001.pcd", "val_0000_primitives.json",
                                 "val_0001_primitives.json", "val_manifest.json", "classes.txt"})
    EXPECT_TRUE(std::filesystem::exists(set_dir + "/" + file)) << file;
  EXPECT_EQ(read_cloud_tags(set_dir + "/val_0001.pcd").at("seed"), "2001");
  std::ifstream in(set_dir + "/val_manifest.json");
  std::stringstream manifest;
  manifest << in.rdbuf();
  EXPECT_NE(manifest.str().find("\"seed\": 2000"), std::string::npos) << manifest.str();
  EXPECT_NE(manifest.str().find("\"label_radius\": 0.025"), std::string::npos);
  EXPECT_EQ(read_class_map(set_dir + "/classes.txt").to_text(), ClassMap::taxonomy().to_text());
}

TEST(SynthCli, WritesTheTruePrimitivesBesideTheScene) {
  test::TempDir dir;
  const std::string json = dir.file("truth.json");
  const Result r =
      run("--scene primitives --seed 3 -q -o " + dir.file("p.pcd") + " --primitives " + json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(json);
  std::stringstream text;
  text << in.rdbuf();
  // The format of primlabel-eval --primitives, read back by its own parser.
  const std::vector<primitives::Primitive> truth = primitives::parse_primitives_json(text.str());
  std::map<primitives::PrimitiveKind, int> seen;
  for (const primitives::Primitive& p : truth)
    if (p.points >= 50) ++seen[p.kind()];
  // The primitives scene has boxes and lids, cans and mugs, a ball and a bowl, and a ring.
  EXPECT_GE(seen[primitives::PrimitiveKind::kPlane], 4);
  EXPECT_GE(seen[primitives::PrimitiveKind::kCylinder], 3);
  EXPECT_GE(seen[primitives::PrimitiveKind::kSphere], 2);
  EXPECT_EQ(seen[primitives::PrimitiveKind::kTorus], 1);
  EXPECT_NE(text.str().find("\"object\": 6"), std::string::npos);
}

TEST(SynthCli, UsageErrorsExitWith2AndOneLine) {
  for (const std::string args :
       {"--scene table", "--sensor lidar -o x.pcd", "--radius -1 -o x.pcd", "--set train -o x.pcd",
        "--set train --out-dir d", "--count 3 -o x.pcd", "--scene kitchen -o x.pcd",
        "--seed x -o x.pcd"}) {
    const Result r = run(args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << args << ": " << r.output;
    EXPECT_NE(r.output.find("primlabel-synth: usage error"), std::string::npos) << r.output;
  }
}

TEST(SynthCli, UnwritableOutputExitsWith1NamingThePath) {
  const Result r = run("--scene primitives --seed 1 -o /nonexistent/dir/out.pcd");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/dir/out.pcd"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace primlabel
