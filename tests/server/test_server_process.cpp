// The real primlabel-server binary on 127.0.0.1 with ephemeral ports (read back from its
// "event=listening" log line): labeling through the generated stubs, /metrics, graceful
// shutdown on SIGTERM (in-flight requests finish, exit 0), the drain deadline, configuration
// precedence (flags > environment > file) and start-up errors (bad flags, a --default-model or
// --pin naming nothing loaded, a port already in use).

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "primlabel/ops/metrics_endpoint.hpp"
#include "proc_status.hpp"
#include "server_test_util.hpp"

namespace primlabel::servertest {
namespace {

using testing::random_label_model;
using testing::table_with_box_cloud;

std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// primlabel-server as a child process; its stderr goes to a log file.
class ServerProcess {
 public:
  ServerProcess(const std::vector<std::string>& args,
                const std::vector<std::pair<std::string, std::string>>& env = {})
      : dir_("process"), log_(dir_.path() / "server.log") {
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 2);
      dup2(fd, 1);
      for (const auto& [name, value] : env) setenv(name.c_str(), value.c_str(), 1);
      std::vector<char*> argv;
      const std::string binary = std::string(PRIMLABEL_BIN_DIR) + "/primlabel-server";
      argv.push_back(const_cast<char*>(binary.c_str()));
      for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
      argv.push_back(nullptr);
      execv(binary.c_str(), argv.data());
      _exit(127);
    }
  }
  ~ServerProcess() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }

  // Waits for the listening line (or the process's end); false if it never came.
  bool wait_listening() {
    const std::regex line(R"(event=listening .*port=(\d+) metrics_port=(\d+))");
    for (int i = 0; i < 600; ++i) {
      std::smatch match;
      const std::string text = log();
      if (std::regex_search(text, match, line)) {
        port = std::stoi(match[1]);
        metrics_port = std::stoi(match[2]);
        return true;
      }
      if (exit_code(0) != kRunning) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }

  static constexpr int kRunning = -1000;
  // The exit code once it exited within `wait_ms`, else kRunning (-1 when killed by a signal).
  int exit_code(int wait_ms) {
    if (exited_) return code_;
    for (int waited = 0;; waited += 20) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        return code_;
      }
      if (waited >= wait_ms) return kRunning;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  void signal(int number) { kill(pid_, number); }
  pid_t pid() const { return pid_; }
  std::string log() const { return read_text(log_); }
  bool logged(const std::string& text) const { return log().find(text) != std::string::npos; }

  int port = 0, metrics_port = 0;

 private:
  TempDir dir_;
  fs::path log_;
  pid_t pid_ = -1;
  bool exited_ = false;
  int code_ = 0;
};

class ServerBinary : public ::testing::Test {
 protected:
  ServerBinary() : repo_("binrepo"), model_(random_label_model("tabletop", "1")) {
    write_model(repo_.path(), model_);
  }
  std::vector<std::string> base_args() const {
    return {"--models",    repo_.path().string(), "--listen",
            "127.0.0.1:0", "--metrics-listen",    "127.0.0.1:0"};
  }
  TempDir repo_;
  LabelModel model_;
};

TEST_F(ServerBinary, LabelsServesMetricsAndStopsCleanlyOnSigterm) {
  ServerProcess server(base_args());
  ASSERT_TRUE(server.wait_listening()) << server.log();
  auto channel = channel_to(server.port);
  EXPECT_EQ(health_status(channel, ""), "SERVING");
  auto stub = v1::Labeler::NewStub(channel);
  const PointCloud cloud = table_with_box_cloud(0.01f);
  const LabelAnswer answer = label_stream(*stub, scan_requests(cloud, header_for("tabletop")));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.labels, reference_labels(model_, cloud));

  const auto samples = scrape_metrics(server.metrics_port);
  EXPECT_EQ(scrape::sum_samples(samples, "primlabel_requests_total",
                                {{"method", "Label"}, {"status", "OK"}}),
            1.0);
  EXPECT_EQ(scrape::sum_samples(samples, "primlabel_model_info",
                                {{"model", "tabletop"}, {"version", "1"}}),
            1.0);

  server.signal(SIGTERM);
  EXPECT_EQ(server.exit_code(30000), 0) << server.log();
  EXPECT_TRUE(server.logged("event=signal signal=SIGTERM"));
  EXPECT_TRUE(server.logged("event=stopped"));
  const std::regex request_line(
      R"(event=request method=Label request_id=\S+ scan_id=s1 model=tabletop version=1 points=\d+ .*duration_ms=\S+ status=OK.* cascaded=\d+ )");
  EXPECT_TRUE(std::regex_search(server.log(), request_line)) << server.log();
}

TEST_F(ServerBinary, SigtermLetsInFlightRequestsFinishAndRefusesNewOnes) {
  std::vector<std::string> args = base_args();
  args.insert(args.end(), {"--drain-seconds", "60"});
  ServerProcess server(args);
  ASSERT_TRUE(server.wait_listening()) << server.log();
  auto channel = channel_to(server.port);
  auto stub = v1::Labeler::NewStub(channel);
  const PointCloud big = table_with_box_cloud(0.004f);  // seconds of work

  LabelAnswer in_flight;
  std::thread client([&] { in_flight = label_stream(*stub, scan_requests(big, header_for())); });
  // Wait until the server is labeling it.
  for (int i = 0; i < 400; ++i) {
    const auto samples = scrape_metrics(server.metrics_port);
    if (scrape::sum_samples(samples, "primlabel_inflight_requests") >= 1) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  server.signal(SIGTERM);
  for (int i = 0; i < 400 && !server.logged("event=shutting_down"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(server.logged("event=shutting_down"));
  // New calls are refused while the old one drains.
  EXPECT_NE(health_status(channel, ""), "SERVING");
  const LabelAnswer refused = label_stream(
      *stub, scan_requests(table_with_box_cloud(0.02f), header_for()), std::chrono::seconds(10));
  EXPECT_FALSE(refused.status.ok());
  client.join();
  ASSERT_TRUE(in_flight.status.ok()) << in_flight.status.error_message();
  EXPECT_EQ(in_flight.labels.size(), big.size());
  EXPECT_EQ(server.exit_code(60000), 0) << server.log();
}

TEST_F(ServerBinary, TheDrainDeadlineCancelsWhatIsLeft) {
  std::vector<std::string> args = base_args();
  ServerProcess server(args, {{"PRIMLABEL_DRAIN_SECONDS", "0.2"}});
  ASSERT_TRUE(server.wait_listening()) << server.log();
  auto stub = v1::Labeler::NewStub(channel_to(server.port));
  const PointCloud big = table_with_box_cloud(0.003f);
  LabelAnswer in_flight;
  std::thread client([&] { in_flight = label_stream(*stub, scan_requests(big, header_for())); });
  for (int i = 0; i < 400 && !server.logged("event=request") && !server.logged("receive_ms"); ++i) {
    if (scrape::sum_samples(scrape_metrics(server.metrics_port), "primlabel_inflight_requests") >=
        1)
      break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  server.signal(SIGTERM);
  client.join();
  EXPECT_FALSE(in_flight.status.ok());
  EXPECT_EQ(server.exit_code(30000), 0) << server.log();
  EXPECT_TRUE(server.logged("drain_ms=200"));
}

TEST_F(ServerBinary, FlagsWinOverEnvironmentWhichWinsOverTheConfigFile) {
  TempDir dir("config");
  const fs::path config = dir.path() / "server.conf";
  std::ofstream(config) << "# primlabel-server settings\nqueue = 7\nworkers = 1\n"
                        << "models = " << repo_.path().string() << "\n";
  const std::vector<std::string> ports{"--listen", "127.0.0.1:0", "--metrics-listen",
                                       "127.0.0.1:0"};
  auto queue_of = [&](std::vector<std::string> args,
                      const std::vector<std::pair<std::string, std::string>>& env) {
    args.insert(args.end(), ports.begin(), ports.end());
    ServerProcess server(args, env);
    if (!server.wait_listening()) return std::string("no start: ") + server.log();
    std::smatch match;
    const std::string text = server.log();
    server.signal(SIGINT);
    EXPECT_EQ(server.exit_code(30000), 0);
    return std::regex_search(text, match, std::regex(R"(queue=(\d+))")) ? match[1].str()
                                                                        : std::string("?");
  };
  EXPECT_EQ(queue_of({"--config", config.string()}, {}), "7");
  EXPECT_EQ(queue_of({"--config", config.string()}, {{"PRIMLABEL_QUEUE", "5"}}), "5");
  EXPECT_EQ(queue_of({"--config", config.string(), "--queue", "3"}, {{"PRIMLABEL_QUEUE", "5"}}),
            "3");
  EXPECT_EQ(queue_of({}, {{"PRIMLABEL_CONFIG", config.string()}}), "7");
}

TEST_F(ServerBinary, StartupErrorsExitNonZeroWithAReason) {
  {
    ServerProcess server({"--listen", "127.0.0.1:0"});  // --models missing
    EXPECT_EQ(server.exit_code(30000), 2);
    EXPECT_TRUE(server.logged("--models")) << server.log();
  }
  {
    ServerProcess server(
        {"--models", "/nonexistent/models", "--listen", "127.0.0.1:0", "--metrics-listen", ""});
    EXPECT_EQ(server.exit_code(30000), 1);
    EXPECT_TRUE(server.logged("event=startup_failed")) << server.log();
  }
  {
    // A /metrics address that is taken, or one this build cannot serve: a reason, no abort.
    ops::MetricsEndpoint taken("127.0.0.1:0", {});
    const std::string busy = "127.0.0.1:" + std::to_string(taken.port());
    for (const std::string& address : {busy, std::string("[::1]:9464"), std::string("x:99999")}) {
      ServerProcess server({"--models", repo_.path().string(), "--listen", "127.0.0.1:0",
                            "--metrics-listen", address});
      EXPECT_EQ(server.exit_code(30000), 1) << address << ": " << server.log();
      EXPECT_TRUE(server.logged("event=startup_failed")) << server.log();
      EXPECT_TRUE(server.logged("cannot serve /metrics on '" + address + "'")) << server.log();
    }
  }
  {
    ServerProcess server(
        {"--models", repo_.path().string(), "--listen", "127.0.0.1:0", "--pin", "nonsense"});
    EXPECT_EQ(server.exit_code(30000), 2);
    EXPECT_TRUE(server.logged("MODEL=VERSION")) << server.log();
  }
}

TEST_F(ServerBinary, ADefaultModelOrPinNamingNothingLoadedFailsStartup) {
  struct Case {
    std::vector<std::string> flags;
    std::string says;
  };
  const std::vector<Case> cases{
      {{"--default-model", "nosuch"},
       "--default-model 'nosuch' is not a loaded model; loaded: "
       "tabletop (1)"},
      {{"--pin", "tabletop=9"},
       "--pin tabletop=9: model 'tabletop' has no version '9'; loaded: tabletop (1)"},
      {{"--pin", "other=1"}, "--pin other=1: model 'other' is not loaded; loaded: tabletop (1)"}};
  for (const Case& c : cases) {
    std::vector<std::string> args = base_args();
    args.insert(args.end(), c.flags.begin(), c.flags.end());
    ServerProcess server(args);
    EXPECT_EQ(server.exit_code(30000), 2) << server.log();
    EXPECT_TRUE(server.logged(c.says + "\n")) << server.log();  // one line
    EXPECT_FALSE(server.logged("event=listening")) << server.log();
  }
}

TEST_F(ServerBinary, InsecureAdminIsWarnedAtStartup) {
  std::vector<std::string> args = base_args();
  {
    ServerProcess server(args);
    ASSERT_TRUE(server.wait_listening()) << server.log();
    EXPECT_TRUE(server.logged(" admin=off ")) << server.log();
    EXPECT_FALSE(server.logged("event=insecure_admin")) << server.log();
  }
  args.push_back("--insecure-admin");
  ServerProcess server(args);
  ASSERT_TRUE(server.wait_listening()) << server.log();
  EXPECT_TRUE(server.logged("level=warn event=insecure_admin")) << server.log();
  EXPECT_TRUE(server.logged(" admin=insecure ")) << server.log();
}

TEST_F(ServerBinary, ASecondServerOnAPortInUseExitsNamingTheAddress) {
  ServerProcess first(base_args());
  ASSERT_TRUE(first.wait_listening()) << first.log();
  const std::string address = "127.0.0.1:" + std::to_string(first.port);
  ServerProcess second(
      {"--models", repo_.path().string(), "--listen", address, "--metrics-listen", ""});
  EXPECT_EQ(second.exit_code(30000), 1) << second.log();
  EXPECT_TRUE(second.logged("cannot listen on " + address)) << second.log();
  EXPECT_FALSE(second.logged("event=listening")) << second.log();
  EXPECT_EQ(health_status(channel_to(first.port), ""), "SERVING");
  first.signal(SIGTERM);
  EXPECT_EQ(first.exit_code(30000), 0) << first.log();
}

long status_kb(pid_t pid, const std::string& field) {
  return testing::proc_status(field, std::to_string(pid));
}

TEST_F(ServerBinary, MemoryGoesBackToTheSystemAfterALargeRequest) {
  // Small radii keep the 110k-point scan quick to describe.
  LabelModel model = random_label_model("big", "1");
  model.features.normals = Neighborhood::Radius(0.006f);
  model.features.features = Neighborhood::Radius(0.012f);
  TempDir repo("bigrepo");
  write_model(repo.path(), model);
  ServerProcess server({"--models", repo.path().string(), "--listen", "127.0.0.1:0",
                        "--metrics-listen", "127.0.0.1:0"});
  ASSERT_TRUE(server.wait_listening()) << server.log();
  const long idle_kb = status_kb(server.pid(), "VmRSS");
  auto stub = v1::Labeler::NewStub(channel_to(server.port));
  const PointCloud cloud = table_with_box_cloud(0.0018f);
  ASSERT_GT(cloud.size(), 100000u);
  v1::ScanHeader header = header_for("big");
  header.mutable_options()->set_return_descriptors(true);
  const LabelAnswer answer = label_stream(*stub, scan_requests(cloud, header));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  // The answer has been sent and the reactor is gone once the request line is logged.
  for (int i = 0; i < 100 && !server.logged("event=request"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const long peak_kb = status_kb(server.pid(), "VmHWM");
  // glibc kept most of the peak (224 of 455 MB after a 307k frame) before the trim, which comes
  // once no large request has ended for kTrimWhenQuietFor (1 s): wait for it, bounded.
  long after_kb = status_kb(server.pid(), "VmRSS");
  for (int i = 0; i < 100 && after_kb - idle_kb >= (peak_kb - idle_kb) / 4; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    after_kb = status_kb(server.pid(), "VmRSS");
  }
  EXPECT_LT(after_kb - idle_kb, (peak_kb - idle_kb) / 4)
      << "idle " << idle_kb << " kB, peak " << peak_kb << " kB, after " << after_kb << " kB";
}

}  // namespace
}  // namespace primlabel::servertest
