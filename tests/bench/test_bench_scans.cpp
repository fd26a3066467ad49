// `primlabel-bench pipeline --scans`: a file of one's own (a held-out real frame) is labeled with
// the model given, a row named by the file; without a model it refuses in one line.

#include <gtest/gtest.h>

#include <filesystem>

#include "test_util.hpp"

namespace primlabel {
namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(BenchScans, AFileIsLabeledWithTheModelGiven) {
  if (!std::filesystem::exists(test::binary("primlabel-bench")))
    GTEST_SKIP() << "benchmarks not built";
  const auto r =
      test::run_command(test::binary("primlabel-bench") + " pipeline --model " +
                        test::test_data("models/crf_before_run_context.plm") + " --scans " +
                        test::test_data("samples/bun0.pcd") + " --threads 1 --compare-cascade");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output,
                       "\n"
                       "bun0 "))
      << r.output;  // a row named by the file
  EXPECT_TRUE(
      contains(r.output, "\"sensor\":\"bun0\",\"model\":\"crf_before_run_context-cascade\""))
      << r.output;
  EXPECT_TRUE(contains(r.output, "\"points\":397,")) << r.output;  // bun0's own points
}

TEST(BenchScans, WithoutAModelItRefusesInOneLine) {
  if (!std::filesystem::exists(test::binary("primlabel-bench")))
    GTEST_SKIP() << "benchmarks not built";
  const auto r = test::run_command(test::binary("primlabel-bench") + " pipeline --scans " +
                                   test::test_data("samples/bun0.pcd"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  EXPECT_TRUE(contains(r.output, "--model")) << r.output;
}

}  // namespace
}  // namespace primlabel
