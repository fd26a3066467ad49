// --compare-pcl in a build without PCL says why: the CMake option turned off, or (the usual
// case, the option being ON by default) PCL not found at configure time. In a build with PCL
// the comparison runs.

#include <gtest/gtest.h>

#include "pcl_availability.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(BenchPcl, TheReasonNamesTheOptionOnlyWhenItIsOff) {
  const std::string off = bench::pcl_unavailable_reason(false, "PCL 1.13");
  EXPECT_TRUE(contains(off, "-DPRIMLABEL_WITH_PCL=OFF")) << off;
  const std::string missing = bench::pcl_unavailable_reason(true, "PCL 1.13");
  EXPECT_TRUE(contains(missing, "PCL 1.13 was not found")) << missing;
  EXPECT_TRUE(contains(missing, "libpcl-dev")) << missing;
  EXPECT_FALSE(contains(missing, "=OFF")) << missing;
  EXPECT_FALSE(contains(missing, "-DPRIMLABEL_WITH_PCL=ON")) << missing;  // it is on already
}

TEST(BenchPcl, ComparePclRunsOrSaysWhyInOneLine) {
  if (!std::filesystem::exists(test::binary("primlabel-bench")))
    GTEST_SKIP() << "benchmarks not built";
  const auto r = test::run_command(
      test::binary("primlabel-bench") + " features " + test::test_data("samples/bun0.pcd") +
      " --normal-k 10 --feature-k 10 --threads 1 --repeat 1 --descriptor fpfh "
      "--compare-pcl");
  if (r.exit_code == 0) {
    EXPECT_TRUE(contains(r.output, "pcl")) << r.output;  // built with PCL: it compared
    return;
  }
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  // The reason's fixed part: what the benchmark names as missing varies with the benchmark.
  if (PRIMLABEL_WITH_PCL_OPTION) {
    EXPECT_TRUE(contains(r.output, "was not found when this build was configured")) << r.output;
    EXPECT_TRUE(contains(r.output, "libpcl-dev")) << r.output;
  } else {
    EXPECT_TRUE(contains(r.output, "-DPRIMLABEL_WITH_PCL=OFF")) << r.output;
  }
}

// `scaling` prints a row per thread count and one JSON line, with PCL's figures when the build
// has PCL (null otherwise).
TEST(BenchScaling, ARowPerThreadCountAndPclWhenBuilt) {
  if (!std::filesystem::exists(test::binary("primlabel-bench")))
    GTEST_SKIP() << "benchmarks not built";
  const auto r = test::run_command(test::binary("primlabel-bench") + " scaling --input " +
                                   test::test_data("samples/bun0.pcd") +
                                   " --threads 1,3 --repeat 1 --normal-radius 0.004"
                                   " --feature-radius 0.008 2>/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json::Json line = json::Json::parse(r.output.substr(r.output.rfind("{\"bench\"")));
  ASSERT_EQ(line["rows"].size(), 2u) << r.output;
  EXPECT_EQ(line["rows"][1]["threads"], 3);
  for (const auto& row : line["rows"]) {
    EXPECT_GT(row["normals_pts_s"].get<double>(), 0.0) << r.output;
    EXPECT_GT(row["fpfh_pts_s"].get<double>(), 0.0) << r.output;
    const json::Json& pcl = row["pcl_fpfh_pts_s"];
    EXPECT_TRUE(pcl.is_null() || pcl.get<double>() > 0.0) << r.output;
    if (!PRIMLABEL_WITH_PCL_OPTION) EXPECT_TRUE(pcl.is_null()) << r.output;
  }
}

}  // namespace
}  // namespace primlabel
