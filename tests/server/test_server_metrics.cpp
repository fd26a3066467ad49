// The service's metrics on prometheus-cpp: the `model` label takes only loaded model names,
// primlabel_build_info, the process_* metrics read from /proc, and the /metrics endpoint's
// address checks and start-up errors.

#include <fcntl.h>
#include <prometheus/text_serializer.h>
#include <unistd.h>

#include <chrono>
#include <regex>
#include <set>

#include "primlabel/ops/metrics_endpoint.hpp"
#include "primlabel/ops/proc_self.hpp"
#include "primlabel/ops/process_collector.hpp"
#include "primlabel/ops/server_metrics.hpp"
#include "server_test_util.hpp"

namespace primlabel::servertest {
namespace {

using ops::civetweb_listening_port;
using ops::MetricsEndpoint;
using scrape::sum_samples;
using testing::random_label_model;
using testing::table_with_box_cloud;

// Values of label `label` among the samples named `name`.
std::set<std::string> label_values(const std::vector<scrape::Sample>& samples,
                                   const std::string& name, const std::string& label) {
  std::set<std::string> values;
  for (const auto& sample : samples)
    if (sample.name == name && sample.labels.contains(label))
      values.insert(sample.labels.at(label));
  return values;
}

TEST(ServerMetrics, ModelLabelTakesOnlyLoadedModels) {
  ops::ServerMetrics metrics;
  metrics.set_models({{"tabletop", "2"}}, 2);
  for (int i = 0; i < 1000; ++i) {
    const std::string fake = "fake-" + std::to_string(i);
    metrics.request_finished("Label", fake, "NOT_FOUND", 0.001);
    metrics.points_labeled(fake, 1);
  }
  metrics.request_finished("Label", "tabletop", "OK", 0.01);
  metrics.points_labeled("tabletop", 5);
  const auto samples = scrape::parse_exposition(metrics.serialize());
  EXPECT_EQ(label_values(samples, "primlabel_requests_total", "model"),
            (std::set<std::string>{"tabletop", "unknown"}));
  EXPECT_EQ(label_values(samples, "primlabel_points_total", "model"),
            (std::set<std::string>{"tabletop", "unknown"}));
  EXPECT_EQ(sum_samples(samples, "primlabel_requests_total", {{"model", "unknown"}}), 1000.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_points_total", {{"model", "tabletop"}}), 5.0);

  // Once unloaded, a model's name is no longer a label value (its old series stay).
  metrics.set_models({}, 0);
  metrics.request_finished("Label", "tabletop", "NOT_FOUND", 0.01);
  const auto after = scrape::parse_exposition(metrics.serialize());
  EXPECT_EQ(sum_samples(after, "primlabel_requests_total", {{"model", "unknown"}}), 1001.0);
  EXPECT_EQ(sum_samples(after, "primlabel_requests_total", {{"model", "tabletop"}}), 1.0);
}

TEST(ServerMetrics, ARequestForAModelThatDoesNotExistCountsAsUnknown) {
  TestServer server({random_label_model("m", "1")});
  const PointCloud cloud = table_with_box_cloud(0.02f);
  EXPECT_EQ(label_cloud(*server.stub, cloud, header_for("no-such-model")).status.error_code(),
            grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(label_stream(*server.stub, scan_requests(cloud, header_for("another-fake")))
                .status.error_code(),
            grpc::StatusCode::NOT_FOUND);
  ASSERT_TRUE(label_cloud(*server.stub, cloud, header_for("m")).status.ok());
  const auto samples = scrape_metrics(server.server->metrics_port());
  EXPECT_EQ(sum_samples(samples, "primlabel_requests_total",
                        {{"model", "unknown"}, {"status", "NOT_FOUND"}}),
            2.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_requests_total", {{"model", "m"}, {"status", "OK"}}),
            1.0);
  for (const auto& value : label_values(samples, "primlabel_requests_total", "model"))
    EXPECT_TRUE(value == "m" || value == "unknown") << value;
}

TEST(ServerMetrics, BuildInfoNamesTheVersionAndGit) {
  const auto samples = scrape::parse_exposition(ops::ServerMetrics().serialize());
  std::vector<scrape::Sample> info;
  for (const auto& sample : samples)
    if (sample.name == "primlabel_build_info") info.push_back(sample);
  ASSERT_EQ(info.size(), 1u);
  EXPECT_EQ(info[0].value, 1.0);
  EXPECT_EQ(info[0].labels.at("version"), PRIMLABEL_PROJECT_VERSION);
  EXPECT_TRUE(std::regex_match(info[0].labels.at("git"), std::regex("[A-Za-z0-9._+-]+")))
      << info[0].labels.at("git");
}

TEST(ProcessMetrics, ReadFromProcSelf) {
  const auto value = [](const std::string& name) {
    const auto samples = scrape::parse_exposition(
        prometheus::TextSerializer().Serialize(ops::ProcessCollector().Collect()));
    std::size_t found = 0;
    for (const auto& sample : samples) found += sample.name == name;
    EXPECT_EQ(found, 1u) << name;
    return sum_samples(samples, name);
  };
  EXPECT_GT(value("process_resident_memory_bytes"), 1e6);
  EXPECT_GE(value("process_virtual_memory_bytes"), value("process_resident_memory_bytes"));
  EXPECT_GE(value("process_cpu_seconds_total"), 0.0);
  const double now =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  const double start = value("process_start_time_seconds");
  EXPECT_LE(start, now + 1);
  EXPECT_GT(start, now - 3600);  // this test process started moments ago
  const double open = value("process_open_fds");
  EXPECT_GE(open, 3.0);
  EXPECT_LE(open, value("process_max_fds"));
  std::vector<int> fds;
  for (int i = 0; i < 10; ++i) fds.push_back(::open("/dev/null", O_RDONLY));
  EXPECT_GE(value("process_open_fds"), open + 10);
  for (int fd : fds) ::close(fd);
}

TEST(ProcessMetrics, WithoutProcOnlyTheLimitsAreLeft) {
  const auto families = ops::ProcessCollector("/nonexistent/proc", "/nonexistent/stat").Collect();
  ASSERT_LE(families.size(), 1u);  // none when RLIMIT_NOFILE is unlimited
  for (const auto& family : families) EXPECT_EQ(family.name, "process_max_fds");
}

TEST(ProcSelf, ParsesStatLinesWhoseCommandNameHasBlanksAndParentheses) {
  const std::string line =
      "4242 (a) (b c)) S 1 4242 4242 0 -1 4194560 500 0 0 0 "
      "250 125 0 0 20 0 8 0 98765 123456789 3000 18446744073709551615 1 1 0 0 0 0 0 0 0 0 0 0 "
      "17 1 0 0 0 0 0\n";
  const auto stat = ops::parse_proc_stat(line);
  ASSERT_TRUE(stat);
  EXPECT_EQ(stat->utime_ticks, 250u);
  EXPECT_EQ(stat->stime_ticks, 125u);
  EXPECT_EQ(stat->start_ticks, 98765u);
  EXPECT_EQ(stat->virtual_bytes, 123456789u);
  EXPECT_EQ(stat->resident_pages, 3000);
  EXPECT_FALSE(ops::parse_proc_stat(""));
  EXPECT_FALSE(ops::parse_proc_stat("4242 (x) S 1 2 3"));  // truncated
  EXPECT_FALSE(ops::parse_proc_stat(")( S 1"));
  EXPECT_FALSE(ops::parse_proc_stat(std::regex_replace(line, std::regex(" 250 "), " x50 ")));
  EXPECT_FALSE(ops::parse_proc_stat(std::regex_replace(line, std::regex(" 250 "), " -250 ")));

  EXPECT_EQ(ops::parse_boot_time("cpu 1 2 3\nintr 5 6\nbtime 1700000000\nprocesses 9\n"),
            1700000000u);
  EXPECT_FALSE(ops::parse_boot_time("cpu 1 2 3\n"));
  EXPECT_FALSE(ops::parse_boot_time("btime soon\n"));
  EXPECT_FALSE(ops::parse_boot_time("btime 1 2\n"));
}

TEST(MetricsEndpoint, AcceptsOnePlainHostAndPort) {
  EXPECT_EQ(civetweb_listening_port("127.0.0.1:0"), "127.0.0.1:0");
  EXPECT_EQ(civetweb_listening_port("localhost:9464"), "localhost:9464");
  EXPECT_EQ(civetweb_listening_port(":9464"), "9464");
  for (const char* bad :
       {"", "9464", "127.0.0.1:", "127.0.0.1:65536", "127.0.0.1:-1", "127.0.0.1:80s",
        "127.0.0.1:80,127.0.0.1:81", "[::1]:80", "a b:80", "127.0.0.1: 80", "127.0.0.1:+80"})
    EXPECT_THROW(civetweb_listening_port(bad), std::invalid_argument) << bad;
  EXPECT_THROW(civetweb_listening_port(std::string(300, 'h') + ":80"), std::invalid_argument);
}

TEST(MetricsEndpoint, PortZeroPicksAPortAndABusyOneIsAClearError) {
  ops::ServerMetrics metrics;
  MetricsEndpoint endpoint("127.0.0.1:0", metrics.collectables());
  ASSERT_GT(endpoint.port(), 0);
  EXPECT_EQ(sum_samples(scrape_metrics(endpoint.port()), "primlabel_build_info"), 1.0);
  const std::string busy = "127.0.0.1:" + std::to_string(endpoint.port());
  try {
    MetricsEndpoint second(busy, metrics.collectables());
    ADD_FAILURE() << "bound a busy port";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cannot serve /metrics on '" + busy + "': ", 0), 0u)
        << e.what();
  }
  try {
    MetricsEndpoint bad("127.0.0.1:99999", metrics.collectables());
    ADD_FAILURE() << "bound port 99999";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'127.0.0.1:99999': the port must be"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace primlabel::servertest
