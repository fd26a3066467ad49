// The client tools against the real primlabel-server process on 127.0.0.1 (ephemeral ports):
// the CLI, the library's stream and unary calls agreeing, the uploader surviving a server killed
// and restarted mid-upload (and its own SIGKILL) with every scan labeled exactly once, and the
// load generator's counts matching the server's Prometheus counters.

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>

#include "primlabel/client/client.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/model/label_model.hpp"
#include "process.hpp"
#include "random_label_model.hpp"
#include "test_util.hpp"
#include "upload/spool.hpp"
#include "upload/uploader.hpp"

namespace primlabel {
namespace {

namespace fs = std::filesystem;
using test::Process;

// A primlabel-server child on 127.0.0.1, killed when the object dies.
class ServerProcess {
 public:
  // Port 0: any free port; the bound ports are read from the "listening" log line.
  ServerProcess(const std::string& models, const std::string& log, int port = 0)
      : process_({test::binary("primlabel-server"), "--models", models, "--listen",
                  "127.0.0.1:" + std::to_string(port), "--metrics-listen", "127.0.0.1:0",
                  "--reload-seconds", "0"},
                 log) {
    const auto line = process_.wait_for_log("event=listening ([^\n]*)", std::chrono::seconds(60));
    if (!line) throw std::runtime_error("the server did not start:\n" + process_.log());
    std::smatch m;
    if (std::regex_search(*line, m, std::regex(" port=(\\d+)"))) port_ = std::stoi(m[1]);
    if (std::regex_search(*line, m, std::regex(" metrics_port=(\\d+)")))
      metrics_port_ = std::stoi(m[1]);
  }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  std::string metrics_address() const { return "127.0.0.1:" + std::to_string(metrics_port_); }
  int port() const { return port_; }
  Process& process() { return process_; }

 private:
  Process process_;
  int port_ = 0;
  int metrics_port_ = 0;
};

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

std::set<std::string> file_names(const fs::path& dir) {
  std::set<std::string> names;
  if (fs::exists(dir))
    for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

// The labeled clouds in an output directory (not their .classes.json files).
std::set<std::string> cloud_names(const fs::path& dir) {
  std::set<std::string> names;
  for (const std::string& name : file_names(dir))
    if (!name.ends_with(".classes.json")) names.insert(name);
  return names;
}

class ClientE2e : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!fs::exists(test::binary("primlabel-server"))) return;
    dir_ = new test::TempDir();
    // A repository with one small, fast model: <repo>/<name>/<version>/model.plm.
    fs::create_directories(dir_->file("models/random/1"));
    save_model(dir_->file("models/random/1/model.plm"), testing::random_label_model("random"));
    // Scans: the box-on-table scene at 1 cm, each shifted so every scan has its own bytes.
    for (int i = 0; i < kScans; ++i) {
      PointCloud cloud = testing::table_with_box_cloud(0.01f);
      for (auto& p : cloud.xyz) p += Vec3f(0.001f * i, 0, 0);
      write_pcd(scan(i), cloud, PcdEncoding::kBinary);
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override {
    if (!dir_) GTEST_SKIP() << "primlabel-server is not built";
  }

  static std::string scan(int i) { return dir_->file("scan" + std::to_string(i) + ".pcd"); }
  static std::string models() { return dir_->file("models"); }
  static std::string file(const std::string& name) { return dir_->file(name); }

  static constexpr int kScans = 10;
  static inline test::TempDir* dir_ = nullptr;
};

TEST_F(ClientE2e, CliHealthModelsInfoAndLabel) {
  ServerProcess server(models(), file("cli-server.log"));
  const std::string cli = test::binary("primlabel") + " --server " + server.address();
  auto r = test::run_command(cli + " health");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "SERVING\n");
  r = test::run_command(cli + " models");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("random"), std::string::npos) << r.output;
  r = test::run_command(cli + " info random");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("corner"), std::string::npos) << r.output;
  r = test::run_command(cli + " label " + scan(0) + " -o " + file("cli-out.pcd") +
                        " --descriptors --probabilities --png");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PointCloud in = read_cloud(scan(0));
  const PointCloud out = read_cloud(file("cli-out.pcd"));
  ASSERT_EQ(out.labels.size(), in.size());
  for (auto l : out.labels) ASSERT_TRUE(l == 0 || l == 1 || l == 2 || l == 4 || l == 5 || l == 6);
  ASSERT_NE(out.find_field("fpfh"), nullptr);
  std::size_t prob_fields = 0;
  for (const FloatField& f : out.fields) prob_fields += f.name.rfind("prob_", 0) == 0;
  EXPECT_EQ(prob_fields, 5u);  // one per class of the model
  EXPECT_NE(out.find_field("prob_plane"), nullptr);
  EXPECT_TRUE(fs::exists(file("cli-out.png")));
  r = test::run_command(cli + " label --model nope " + scan(0));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
}

TEST_F(ClientE2e, StreamedInSmallChunksAndUnaryGiveTheSameLabels) {
  ServerProcess server(models(), file("lib-server.log"));
  client::ClientOptions options;
  options.address = server.address();
  client::Client client(options);
  EXPECT_EQ(client.health(), client::HealthStatus::kServing);
  const PointCloud cloud = read_cloud(scan(1));
  client::LabelOptions small;
  small.chunk_points = 777;
  small.response_chunk_points = 500;
  small.probabilities = true;
  small.frame_id = "map";
  small.stamp_ns = 123'456'789'012ull;
  const auto streamed = client.label(cloud, small);
  const auto unary = client.label_unary(cloud);
  EXPECT_EQ(streamed.frame_id(), "map");  // echoed by the server
  EXPECT_EQ(streamed.stamp_ns(), 123'456'789'012ull);
  EXPECT_EQ(unary.frame_id(), "");
  ASSERT_EQ(streamed.size(), cloud.size());
  EXPECT_EQ(streamed.labels, unary.labels);
  EXPECT_EQ(streamed.summary.points_received(), cloud.size());
  EXPECT_EQ(streamed.class_ids.size(), 5u);
  EXPECT_EQ(streamed.probabilities.size(), cloud.size() * 5);
}

// The acceptance test: kill -9 the server while the uploader is mid-way, restart it on
// the same port; later kill -9 the uploader itself and start it again. Every scan ends up
// labeled exactly once, in <out>/<scan file stem>.<key>.pcd, and the spool is empty.
TEST_F(ClientE2e, UploaderSurvivesServerAndUploaderKillsWithEveryScanLabeledOnce) {
  const std::string spool = file("up-spool"), out = file("up-out");
  std::vector<std::string> args{test::binary("primlabel-upload"),
                                "--spool",
                                spool,
                                "-o",
                                out,
                                "--backoff-max",
                                "0.5",
                                "--status-interval",
                                "0.5",
                                "--retries",
                                "1",
                                "--deadline",
                                "60"};
  for (int i = 0; i < kScans; ++i) args.push_back(scan(i));
  // Each output named after its scan file, keyed by its content and the (default) options.
  const auto output_of = [&](int i) {
    return client::upload::output_name(client::upload::scan_id(read_bytes(scan(i))), {},
                                       std::filesystem::path(scan(i)).stem().string());
  };
  std::set<std::string> expected;
  for (int i = 0; i < kScans; ++i) {
    expected.insert(output_of(i));
    expected.insert(fs::path(output_of(i)).replace_extension(".classes.json").string());
  }

  auto server = std::make_unique<ServerProcess>(models(), file("up-server1.log"));
  const int port = server->port();
  args.insert(args.begin() + 1, {"--server", server->address()});
  auto uploader = std::make_unique<Process>(args, file("upload1.log"));
  ASSERT_TRUE(
      test::eventually([&] { return cloud_names(out).size() >= 2; }, std::chrono::seconds(120)))
      << uploader->log();
  server->process().kill(SIGKILL);  // mid-upload: no drain, no goodbye
  server.reset();
  // The uploader notices and backs off; nothing it accepted is lost meanwhile.
  EXPECT_TRUE(uploader->wait_for_log("server down", std::chrono::seconds(30))) << uploader->log();
  EXPECT_EQ(file_names(spool + "/scans").size() + cloud_names(out).size(),
            static_cast<std::size_t>(kScans));
  server = std::make_unique<ServerProcess>(models(), file("up-server2.log"), port);
  const std::size_t before_uploader_kill = cloud_names(out).size();
  // Then the uploader itself dies (SIGKILL) part-way, if it has not finished yet.
  test::eventually([&] { return cloud_names(out).size() >= before_uploader_kill + 2; },
                   std::chrono::seconds(120));
  uploader->kill(SIGKILL);
  const std::string first_log = uploader->log();
  uploader = std::make_unique<Process>(args, file("upload2.log"));
  const auto code = uploader->wait_for(std::chrono::seconds(240));
  ASSERT_TRUE(code.has_value()) << uploader->log();
  EXPECT_EQ(*code, 0) << uploader->log();

  EXPECT_EQ(file_names(out), expected) << first_log << uploader->log();  // no extra, no temp files
  EXPECT_TRUE(file_names(spool + "/scans").empty());
  EXPECT_TRUE(file_names(spool + "/failed").empty());
  for (int i = 0; i < kScans; ++i) {
    const PointCloud labeled = read_cloud(out + "/" + output_of(i));
    EXPECT_EQ(labeled.labels.size(), read_cloud(scan(i)).size());
  }
  EXPECT_NE(first_log.find("will retry"), std::string::npos) << first_log;
  if (std::getenv("PRIMLABEL_TEST_VERBOSE")) std::cerr << first_log << uploader->log();
  // The restarted uploader skipped what was done and says so.
  EXPECT_NE(uploader->log().find("left in spool 0"), std::string::npos) << uploader->log();
}

std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::stringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ',')) cells.push_back(cell);
    if (line.ends_with(",")) cells.push_back("");
    rows.push_back(cells);
  }
  return rows;
}

TEST_F(ClientE2e, LoadgenCountsMatchTheServersPrometheusCounters) {
  ServerProcess server(models(), file("load-server.log"));
  for (const std::string calls : {"", " --unary"}) {
    const auto r =
        test::run_command("( " + test::binary("primlabel-loadgen") + " --server " +
                          server.address() + " " + scan(2) + " " + scan(3) + calls +
                          " --requests 6 --concurrency-range 1:3:2 --format csv --metrics-url " +
                          server.metrics_address() + " 2>/dev/null )");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto rows = csv_rows(r.output);
    ASSERT_EQ(rows.size(), 3u) << r.output;
    const auto& header = rows[0];
    const auto column = [&](const std::string& name) {
      return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) -
                                      header.begin());
    };
    for (std::size_t i = 1; i < rows.size(); ++i) {
      ASSERT_EQ(rows[i].size(), header.size()) << r.output;
      EXPECT_EQ(rows[i][column("ok")], "6") << r.output;
      EXPECT_EQ(rows[i][column("errors")], "0") << r.output;
      EXPECT_EQ(rows[i][column("server_requests")], "6") << r.output;
      EXPECT_EQ(rows[i][column("server_by_status")], "OK=6") << r.output;
    }
  }
}

}  // namespace
}  // namespace primlabel
