// Per-point answers near creases (pipeline/crease_points.hpp, LabelingOptions::crease_points): a
// voxel a crease cuts keeps its answer for its majority side only; its points on the far side
// take the label of their side from the marginals of the voxels around them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "primlabel/pipeline/crease_points.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"
#include "random_label_model.hpp"

namespace primlabel {
namespace {

constexpr std::uint32_t kLeft = 1, kRight = 4;  // the two sides' taxonomy ids
constexpr float kVoxel = 0.0068f;               // no cell boundary falls on a 1 mm grid point

// A 30 x 20 mm patch sampled every millimetre, its points left of x = 10.5 mm one class and the
// rest the other, cut into voxels whose marginals are their members' shares of each side (what
// a CRF that saw the mixture would answer) and whose labels are the majority.
struct Patch {
  std::vector<Vec3f> points;
  std::vector<std::uint32_t> truth;
  tabletop::VoxelGrid grid;
  std::vector<std::uint8_t> inferred;
  std::vector<std::uint32_t> labels;
  Eigen::MatrixXf marginals;
  std::vector<std::uint32_t> class_ids = {kLeft, kRight};

  Patch() {
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 30; ++i) {
        points.emplace_back(0.001f * float(i), 0.001f * float(j), 0.0f);
        truth.push_back(i <= 10 ? kLeft : kRight);
      }
    grid = tabletop::voxel_downsample(points, tabletop::finite_indices(points), kVoxel);
    const std::size_t slots = grid.centroids.size();
    inferred.assign(slots, 1);
    labels.resize(slots);
    marginals.resize(Eigen::Index(slots), 2);
    for (std::size_t v = 0; v < slots; ++v) {
      float left = 0, members = 0;
      for (std::uint32_t m = grid.member_offsets[v]; m < grid.member_offsets[v + 1]; ++m) {
        left += truth[grid.members[m]] == kLeft ? 1.0f : 0.0f;
        members += 1.0f;
      }
      marginals(Eigen::Index(v), 0) = left / members;
      marginals(Eigen::Index(v), 1) = 1.0f - left / members;
      labels[v] = left / members > 0.5f ? kLeft : kRight;
    }
    search = std::make_unique<NeighborSearch>(grid.centroids);
  }

  pipeline::CreaseAnswers decide(int threads) const {
    const pipeline::SlotAnswers slots{&grid.centroids, search.get(), inferred,
                                      labels,          &marginals,   class_ids};
    return pipeline::decide_crease_points(points, grid.voxel_of_point, slots, kVoxel,
                                          RunContext{threads});
  }

  std::size_t index(int i, int j) const { return std::size_t(j) * 30 + std::size_t(i); }

  std::unique_ptr<NeighborSearch> search;  // over grid.centroids
};

TEST(CreasePoints, APointOnTheFarSideOfACreaseInsideOneVoxelTakesItsSidesLabel) {
  const Patch patch;
  // The voxels of x = 7..13 mm hold 4 points left of the crease and 3 right: labeled left.
  const std::size_t far_side = patch.index(13, 10);
  ASSERT_EQ(patch.truth[far_side], kRight);
  const std::uint32_t voxel = patch.grid.voxel_of_point[far_side];
  ASSERT_EQ(patch.labels[voxel], kLeft);
  ASSERT_EQ(patch.grid.voxel_of_point[patch.index(7, 10)], voxel);

  const pipeline::CreaseAnswers answers = patch.decide(1);
  const auto at = std::find(answers.points.begin(), answers.points.end(), far_side);
  ASSERT_NE(at, answers.points.end()) << "the point's voxel has a neighbour labeled right";
  const std::size_t j = std::size_t(at - answers.points.begin());
  EXPECT_EQ(answers.labels[j], kRight);
  // Its probabilities are the interpolated ones, and say what its label says.
  EXPECT_GT(answers.probabilities(Eigen::Index(j), 1), answers.probabilities(Eigen::Index(j), 0));
  EXPECT_NEAR(answers.probabilities.row(Eigen::Index(j)).sum(), 1.0f, 1e-5f);
  // The voxel's points deep on its majority side keep the voxel's label.
  const auto deep = std::find(answers.points.begin(), answers.points.end(), patch.index(7, 10));
  ASSERT_NE(deep, answers.points.end());
  EXPECT_EQ(answers.labels[std::size_t(deep - answers.points.begin())], kLeft);
}

TEST(CreasePoints, OnlyPointsOfVoxelsNextToAnotherLabelAreDecidedAndFewerAreWrong) {
  const Patch patch;
  const pipeline::CreaseAnswers answers = patch.decide(1);
  ASSERT_FALSE(answers.points.empty());
  EXPECT_TRUE(std::is_sorted(answers.points.begin(), answers.points.end()));
  std::vector<std::uint32_t> per_point(patch.points.size());
  for (std::size_t i = 0; i < per_point.size(); ++i)
    per_point[i] = patch.labels[patch.grid.voxel_of_point[i]];
  std::size_t wrong_before = 0, wrong_after = 0;
  for (std::size_t i = 0; i < per_point.size(); ++i) wrong_before += per_point[i] != patch.truth[i];
  for (std::size_t j = 0; j < answers.points.size(); ++j) {
    const std::uint32_t i = answers.points[j];
    // Far from the crease (x >= 21 mm: two voxel columns away) nothing is decided.
    EXPECT_LT(patch.points[i].x(), 0.021f);
    per_point[i] = answers.labels[j];
    const Eigen::Index best =
        answers.probabilities(Eigen::Index(j), 1) > answers.probabilities(Eigen::Index(j), 0) ? 1
                                                                                              : 0;
    EXPECT_EQ(answers.labels[j], patch.class_ids[std::size_t(best)]);
  }
  for (std::size_t i = 0; i < per_point.size(); ++i) wrong_after += per_point[i] != patch.truth[i];
  EXPECT_LT(wrong_after, wrong_before);
}

TEST(CreasePoints, TheAnswersDoNotDependOnTheThreadCount) {
  const Patch patch;
  const pipeline::CreaseAnswers one = patch.decide(1), two = patch.decide(2);
  EXPECT_EQ(one.points, two.points);
  EXPECT_EQ(one.labels, two.labels);
  EXPECT_TRUE(one.probabilities == two.probabilities);
}

TEST(CreasePoints, LabelCloudGivesTheSameLabelsAndProbabilitiesOnOneAndTwoThreads) {
  // Node-only, a seed whose labels vary on the table (a coupled random model labels one class).
  const LabelModel model = testing::random_label_model("random", "1", /*seed=*/1);
  pipeline::LabelingOptions options;
  options.voxel_size = 0.005f;
  options.want_probabilities = true;
  options.crease_points = true;
  PointCloud cloud = testing::table_with_box_cloud(0.0025f);
  const pipeline::LabelingResult one = pipeline::label_cloud(model, cloud, options, RunContext{1});
  PointCloud again = testing::table_with_box_cloud(0.0025f);
  const pipeline::LabelingResult two = pipeline::label_cloud(model, again, options, RunContext{2});
  EXPECT_EQ(one.labels, two.labels);
  EXPECT_TRUE(one.probabilities == two.probabilities);

  // Not vacuous: some points leave their voxel's answer, each for its probabilities' argmax.
  PointCloud voxels_only = testing::table_with_box_cloud(0.0025f);
  options.crease_points = false;
  const pipeline::LabelingResult per_voxel =
      pipeline::label_cloud(model, voxels_only, options, RunContext{2});
  std::size_t changed = 0;
  for (std::size_t i = 0; i < one.labels.size(); ++i) {
    if (one.labels[i] == per_voxel.labels[i]) continue;
    ++changed;
    Eigen::Index best = 0;
    one.probabilities.row(Eigen::Index(i)).maxCoeff(&best);
    EXPECT_EQ(one.labels[i], one.class_ids[std::size_t(best)]);
  }
  EXPECT_GT(changed, 0u);
  EXPECT_EQ(one.labeled_points, per_voxel.labeled_points);
}

TEST(CreasePoints, WithoutProbabilitiesNoneAreReturned) {
  const LabelModel model = testing::random_label_model("random", "1", /*seed=*/1);
  pipeline::LabelingOptions options;
  options.voxel_size = 0.005f;
  PointCloud cloud = testing::table_with_box_cloud(0.0025f);
  const pipeline::LabelingResult result =
      pipeline::label_cloud(model, cloud, options, RunContext{2});
  EXPECT_EQ(result.probabilities.size(), 0);
  options.want_probabilities = true;
  PointCloud again = testing::table_with_box_cloud(0.0025f);
  EXPECT_EQ(pipeline::label_cloud(model, again, options, RunContext{2}).labels, result.labels);
}

}  // namespace
}  // namespace primlabel
