// `primlabel-bench crf --model potts --coupling C --seed S`: the case the test
// CrfInference.Speed70k used to print (a prototype model with one coupling of 1 on scene seed 1)
// runs as a benchmark, says which coupling and seed it measured, and times every method.

#include <gtest/gtest.h>

#include <filesystem>

#include "test_util.hpp"

namespace primlabel {
namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(BenchCrf, APottsCouplingAndSeedOfOnesOwnAreMeasured) {
  if (!std::filesystem::exists(test::binary("primlabel-bench")))
    GTEST_SKIP() << "benchmarks not built";
  const auto r = test::run_command(test::binary("primlabel-bench") +
                                   " crf --points 400 --model potts --coupling 1 --seed 1"
                                   " --threads 1 --repeat 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "\"model\":\"potts\",\"seed\":1,\"coupling\":1.0,")) << r.output;
  for (const char* method : {"bp-sum", "bp-max", "mean-field", "node-only"})
    EXPECT_TRUE(contains(r.output, std::string("{\"method\":\"") + method + "\"")) << method;
}

TEST(BenchCrf, ANegativeCouplingIsRefused) {
  if (!std::filesystem::exists(test::binary("primlabel-bench")))
    GTEST_SKIP() << "benchmarks not built";
  const auto r = test::run_command(test::binary("primlabel-bench") +
                                   " crf --points 400 --model potts --coupling -1");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "--coupling")) << r.output;
}

}  // namespace
}  // namespace primlabel
