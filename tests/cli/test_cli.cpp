// End-to-end checks of the command-line tools as a user runs them: exit codes, one-line errors,
// and output files that read back.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/features.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using Result = test::CommandResult;

Result run(const std::string& command) { return test::run_command(command); }

std::string features_tool() { return test::binary("primlabel-features"); }

class FeaturesCli : public ::testing::Test {
 protected:
  void SetUp() override {
    bunny_ = test::shared_data("pcl/bun0.pcd");
    if (!std::filesystem::exists(bunny_)) GTEST_SKIP() << bunny_ << " not present";
  }
  // primlabel-features on the bunny, writing `out` (in the test's folder).
  Result describe_bunny(const std::string& out, const std::string& flags) {
    return run(features_tool() + " " + bunny_ + " -o " + dir_.file(out) + " " + flags);
  }

  std::string bunny_;
  test::TempDir dir_;
};

TEST_F(FeaturesCli, WritesNormalsCurvatureAndFpfh) {
  const Result r =
      describe_bunny("bunny_fpfh.pcd", "--normal-k 10 --feature-radius 0.02 --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PointCloud cloud = read_pcd(dir_.file("bunny_fpfh.pcd"));
  EXPECT_EQ(cloud.size(), 397u);
  EXPECT_TRUE(cloud.has_normals());
  EXPECT_TRUE(cloud.has_curvature());
  const FloatField* fpfh = cloud.find_field("fpfh");
  ASSERT_NE(fpfh, nullptr);
  EXPECT_EQ(fpfh->count, kFpfhSize);
  EXPECT_NE(r.output.find("fpfh: 397 computed, 0 isolated"), std::string::npos) << r.output;
}

TEST_F(FeaturesCli, ThePapersVariantIsNamedAsSuch) {
  const Result r = describe_bunny("bunny_fpfh_paper.pcd",
                                  "--normal-k 10 --feature-radius 0.02 --fpfh-variant paper");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PointCloud cloud = read_pcd(dir_.file("bunny_fpfh_paper.pcd"));
  EXPECT_EQ(cloud.find_field("fpfh"), nullptr);
  const FloatField* paper = cloud.find_field("fpfh_paper");
  ASSERT_NE(paper, nullptr);
  // PCL's rows sum to 300 (three sub-histograms of 100); the paper's add the point's own SPFH.
  double sum = 0;
  for (int b = 0; b < kFpfhSize; ++b) sum += paper->row(5)[b];
  EXPECT_NEAR(sum, 600.0, 0.1);
}

TEST_F(FeaturesCli, PfhToPlyWithInputNormals) {
  const Result r =
      describe_bunny("bunny_pfh.ply", "--use-input-normals --feature-k 10 --descriptor pfh -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");  // quiet
  const PointCloud cloud = read_ply(dir_.file("bunny_pfh.ply"));
  const FloatField* pfh = cloud.find_field("pfh");
  ASSERT_NE(pfh, nullptr);
  EXPECT_EQ(pfh->count, kPfhSize);
}

TEST_F(FeaturesCli, UsageErrorsExitWith2AndOneLine) {
  for (const std::string args :
       {" -o x.pcd --normal-k 10 --normal-radius 0.1", " -o x.pcd --descriptor shot",
        " -o x.pcd --feature-radius -1", "", " -o x.pcd --viewpoint 1,2"}) {
    const Result r = run(features_tool() + " " + bunny_ + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_NE(r.output.find("usage error"), std::string::npos) << r.output;
  }
}

TEST_F(FeaturesCli, RuntimeErrorsExitWith1AndNameTheFile) {
  Result r = run(features_tool() + " /nonexistent/scan.pcd -o " + dir_.file("o.pcd"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("/nonexistent/scan.pcd"), std::string::npos) << r.output;

  PointCloud no_normals = test::random_box(50, 1.0f, 3);
  write_pcd(dir_.file("plain.pcd"), no_normals);
  r = run(features_tool() + " " + dir_.file("plain.pcd") + " -o " + dir_.file("o.pcd") +
          " --use-input-normals");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("has no normal"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir_.file("o.pcd")));
}

}  // namespace
}  // namespace primlabel
