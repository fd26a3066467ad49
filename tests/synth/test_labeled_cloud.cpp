// Labeled clouds as data: header tags round trip, labels map to taxonomy classes, clear errors.

#include <gtest/gtest.h>

#include <functional>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

PointCloud cloud_with_labels(const std::vector<std::uint32_t>& labels) {
  PointCloud cloud = test::random_box(static_cast<int>(labels.size()), 1.0f, 4);
  cloud.labels = labels;
  return cloud;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

TEST(LabeledCloud, TagsRoundTripInPcdAndPly) {
  test::TempDir dir;
  const PointCloud cloud = cloud_with_labels({1, 2, 3, 4});
  const CloudTags tags = {{"label_radius", "0.025"},
                          {"sensor", "lms400"},
                          {"classes", class_map_tag(ClassMap::taxonomy())}};
  for (const std::string file : {"a.pcd", "a.ply"}) {
    write_tagged_cloud(dir.file(file), cloud, tags);
    EXPECT_EQ(read_cloud_tags(dir.file(file)), tags) << file;
    const PointCloud back = read_cloud(dir.file(file));  // readers skip the comment lines
    EXPECT_EQ(back.labels, cloud.labels) << file;
    EXPECT_EQ(back.xyz, cloud.xyz) << file;
  }
  write_cloud(dir.file("plain.pcd"), cloud);
  EXPECT_TRUE(read_cloud_tags(dir.file("plain.pcd")).empty());
  EXPECT_THROW(write_tagged_cloud(dir.file("b.pcd"), cloud, {{"two words", "x"}}),
               std::invalid_argument);
}

TEST(LabeledCloud, MapsUsersLabelsToTaxonomyClasses) {
  test::TempDir dir;
  PointCloud cloud = cloud_with_labels({20, 21, 20, 5, 99});
  cloud.xyz[4] = Vec3f::Constant(NAN);  // invalid point: its label does not matter
  write_pcd(dir.file("scan.pcd"), cloud);
  const ClassMap map = ClassMap::parse("20 plane\n21 cylinder-convex\n5 corner\n");
  const PointCloud mapped = load_labeled_cloud(dir.file("scan.pcd"), map);
  EXPECT_EQ(mapped.labels, (std::vector<std::uint32_t>{1, 2, 1, 6, 0}));
}

TEST(LabeledCloud, ClearErrors) {
  test::TempDir dir;
  write_pcd(dir.file("scan.pcd"), cloud_with_labels({20, 21, 21, 30}));
  const ClassMap map = ClassMap::parse("20 plane\n");
  const std::string unmapped = error_of([&] { load_labeled_cloud(dir.file("scan.pcd"), map); });
  EXPECT_NE(unmapped.find("scan.pcd: label 21 (2 points, and 1 more unmapped labels) is not in the "
                          "class map (it lists 20)"),
            std::string::npos)
      << unmapped;

  PointCloud unlabeled = test::random_box(5, 1.0f, 1);
  write_pcd(dir.file("plain.pcd"), unlabeled);
  const std::string no_labels = error_of([&] { load_labeled_cloud(dir.file("plain.pcd"), map); });
  EXPECT_NE(no_labels.find("plain.pcd: no integer 'label' field"), std::string::npos) << no_labels;
  EXPECT_NE(error_of([&] { load_labeled_cloud(dir.file("none.pcd"), map); }).find("none.pcd"),
            std::string::npos);
}

TEST(LabeledCloud, UsesTheFilesOwnClassList) {
  test::TempDir dir;
  write_tagged_cloud(dir.file("own.pcd"), cloud_with_labels({7, 8}),
                     {{"classes", "7:edge-convex 8:sphere-concave"}});
  EXPECT_EQ(load_labeled_cloud(dir.file("own.pcd")).labels, (std::vector<std::uint32_t>{4, 10}));
  write_pcd(dir.file("ids.pcd"), cloud_with_labels({1, 6}));  // no tag: taxonomy ids
  EXPECT_EQ(load_labeled_cloud(dir.file("ids.pcd")).labels, (std::vector<std::uint32_t>{1, 6}));
}

}  // namespace
}  // namespace primlabel
