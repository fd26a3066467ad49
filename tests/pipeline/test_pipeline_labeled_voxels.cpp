// Training at a model's voxel size (pipeline/labeled_voxels.hpp): voxel centroids as label_cloud
// makes them, each with its members' most frequent label.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "primlabel/pipeline/labeled_voxels.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

PointCloud labeled(std::vector<Vec3f> xyz, std::vector<std::uint32_t> labels) {
  PointCloud cloud;
  cloud.resize_unorganized(xyz.size());
  cloud.xyz = std::move(xyz);
  cloud.labels = std::move(labels);
  return cloud;
}

TEST(LabeledVoxels, EachVoxelTakesItsMembersMostFrequentLabel) {
  // Voxel edge 1 from the lowest corner (0.1, 0.1, 0.1): three points in the first voxel, two in
  // the sixth along x.
  const PointCloud cloud = labeled({{0.1f, 0.1f, 0.1f},
                                    {0.2f, 0.3f, 0.1f},
                                    {0.9f, 0.1f, 0.5f},
                                    {5.4f, 0.2f, 0.2f},
                                    {5.6f, 0.4f, 0.2f}},
                                   {3, 5, 5, 7, 7});
  const PointCloud voxels = pipeline::voxelize_labeled(cloud, 1.0f);
  ASSERT_EQ(voxels.size(), 2u);
  ASSERT_EQ(voxels.labels.size(), 2u);
  EXPECT_EQ(voxels.labels[0], 5u);
  EXPECT_EQ(voxels.labels[1], 7u);
  EXPECT_NEAR(voxels.xyz[0].x(), 0.4f, 1e-6f);  // the members' centroid
  EXPECT_NEAR(voxels.xyz[1].x(), 5.5f, 1e-6f);
  EXPECT_FALSE(voxels.organized());
  EXPECT_FALSE(voxels.has_normals());
}

TEST(LabeledVoxels, ATieGoesToTheLowestIdWhateverThePointOrder) {
  const PointCloud a = labeled({{0.1f, 0.1f, 0.1f}, {0.2f, 0.2f, 0.2f}}, {9, 4});
  const PointCloud b = labeled({{0.2f, 0.2f, 0.2f}, {0.1f, 0.1f, 0.1f}}, {4, 9});
  EXPECT_EQ(pipeline::voxelize_labeled(a, 1.0f).labels.at(0), 4u);
  EXPECT_EQ(pipeline::voxelize_labeled(b, 1.0f).labels.at(0), 4u);
}

TEST(LabeledVoxels, NonFinitePointsAreLeftOutAndTheViewpointKept) {
  PointCloud cloud =
      labeled({{kNaN, kNaN, kNaN}, {0.1f, 0.1f, 0.1f}, {kNaN, 0.0f, 0.0f}}, {2, 1, 2});
  cloud.width = 3;
  cloud.viewpoint.origin = Vec3f(0.0f, 0.0f, -1.0f);
  const PointCloud voxels = pipeline::voxelize_labeled(cloud, 0.01f);
  ASSERT_EQ(voxels.size(), 1u);
  EXPECT_EQ(voxels.labels[0], 1u);  // the NaN points' label 2 does not vote
  EXPECT_EQ(voxels.viewpoint.origin, cloud.viewpoint.origin);
}

TEST(LabeledVoxels, MatchesTheGridLabelCloudDownsamplesTo) {
  // The same centroids as label_cloud's voxel stage, so training sees the served density.
  std::vector<Vec3f> xyz;
  std::vector<std::uint32_t> labels;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      xyz.emplace_back(0.001f * float(i), 0.0013f * float(j), 0.0002f * float((i * j) % 7));
      labels.push_back(std::uint32_t(1 + (i / 10)));
    }
  const PointCloud cloud = labeled(xyz, labels);
  const PointCloud voxels = pipeline::voxelize_labeled(cloud, 0.005f);
  const tabletop::VoxelGrid grid =
      tabletop::voxel_downsample(cloud.xyz, tabletop::finite_indices(cloud.xyz), 0.005f);
  ASSERT_EQ(voxels.xyz.size(), grid.centroids.size());
  for (std::size_t v = 0; v < grid.centroids.size(); ++v)
    EXPECT_EQ(voxels.xyz[v], grid.centroids[v]);
  EXPECT_EQ(*std::min_element(voxels.labels.begin(), voxels.labels.end()), 1u);
  EXPECT_EQ(*std::max_element(voxels.labels.begin(), voxels.labels.end()), 4u);
}

TEST(LabeledVoxels, RefusesCloudsWithoutLabelsAndBadSizes) {
  PointCloud unlabeled;
  unlabeled.resize_unorganized(2);
  EXPECT_THROW(pipeline::voxelize_labeled(unlabeled, 0.01f), std::invalid_argument);
  const PointCloud cloud = labeled({{0.0f, 0.0f, 0.0f}}, {1});
  EXPECT_THROW(pipeline::voxelize_labeled(cloud, 0.0f), std::invalid_argument);
  EXPECT_THROW(pipeline::voxelize_labeled(cloud, -1.0f), std::invalid_argument);
  EXPECT_THROW(pipeline::voxelize_labeled(cloud, kNaN), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel
