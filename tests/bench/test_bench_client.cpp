// `primlabel-bench client`: with no input it labels a synthetic Kinect frame through an
// in-process server and prints the client's stages beside the server's, and the JSON line.
// Only that the rows are there: speed is for the benchmark, not the test.

#include <gtest/gtest.h>

#include <filesystem>

#include "test_util.hpp"

namespace primlabel {
namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(BenchClient, PrintsTheClientStagesBesideTheServers) {
  if (!std::filesystem::exists(test::binary("primlabel-bench")))
    GTEST_SKIP() << "benchmarks not built";
  const auto r = test::run_command(test::binary("primlabel-bench") + " client --reps 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "307200 points (640 x 480)")) << r.output;
  const std::size_t client_row = r.output.find("client stages ms:");
  ASSERT_NE(client_row, std::string::npos) << r.output;
  const std::string row = r.output.substr(client_row, r.output.find('\n', client_row) - client_row);
  for (const char* stage : {" read ", " encode ", " send ", " receive ", " decode ", " write "})
    EXPECT_TRUE(contains(row, stage)) << stage << " in " << row;
  EXPECT_TRUE(contains(r.output, "server stages ms:")) << r.output;
  EXPECT_TRUE(contains(r.output, "beyond the server")) << r.output;
  EXPECT_TRUE(contains(r.output, "\"client_stages\":{")) << r.output;
  EXPECT_TRUE(contains(r.output, "\"write_ms\":")) << r.output;
  EXPECT_TRUE(contains(r.output, "\"server_total_ms\":")) << r.output;
}

TEST(BenchClient, AMissingInputIsAUsageError) {
  if (!std::filesystem::exists(test::binary("primlabel-bench")))
    GTEST_SKIP() << "benchmarks not built";
  const auto r = test::run_command(test::binary("primlabel-bench") + " client /no/such/frame.pcd");
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

}  // namespace
}  // namespace primlabel
