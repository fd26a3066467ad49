// The load generator: statistics, the sweep syntax, server-counter parsing, both loops against
// the fake server, and the tool's report formats and its counts beside the server's.

#include <gtest/gtest.h>
#include <prometheus/counter.h>
#include <prometheus/exposer.h>
#include <prometheus/registry.h>

#include "fake_labeler.hpp"
#include "loadgen/load_runner.hpp"
#include "loadgen/report.hpp"
#include "loadgen/server_counters.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using namespace client::loadgen;
using test::FakeServer;

TEST(LoadgenStats, PercentilesByNearestRank) {
  LoadStats stats;
  for (int ms = 100; ms >= 1; --ms) stats.record_ok(ms / 1000.0, 10);
  EXPECT_DOUBLE_EQ(stats.percentile(50), 0.050);
  EXPECT_DOUBLE_EQ(stats.percentile(90), 0.090);
  EXPECT_DOUBLE_EQ(stats.percentile(99), 0.099);
  EXPECT_DOUBLE_EQ(stats.percentile(100), 0.100);
  EXPECT_DOUBLE_EQ(stats.percentile(0), 0.001);
  EXPECT_DOUBLE_EQ(stats.max(), 0.100);
  EXPECT_EQ(stats.points(), 1000u);
  LoadStats other;
  other.record_error("UNAVAILABLE");
  other.record_error("UNAVAILABLE");
  other.record_error("DEADLINE_EXCEEDED");
  other.record_ok(1.0, 5);
  stats.merge(other);
  EXPECT_EQ(stats.ok(), 101u);
  EXPECT_EQ(stats.errors(), 3u);
  EXPECT_EQ(stats.errors_by_status().at("UNAVAILABLE"), 2u);
  EXPECT_DOUBLE_EQ(stats.max(), 1.0);
  EXPECT_DOUBLE_EQ(LoadStats().percentile(99), 0.0);
}

TEST(LoadgenStats, ConcurrencyRangeLikePerfAnalyzer) {
  EXPECT_EQ(parse_concurrency_range("1:8:2"), (std::vector<int>{1, 3, 5, 7}));
  EXPECT_EQ(parse_concurrency_range("2:4"), (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(parse_concurrency_range("3"), (std::vector<int>{3}));
  for (const char* bad : {"0:4", "4:2", "1:4:0", "x", "1:2:3:4", ""})
    EXPECT_THROW(parse_concurrency_range(bad), std::invalid_argument) << bad;
}

TEST(LoadgenStats, ServerCountsSumModelsPerMethodAndStatus) {
  const std::string text =
      "# TYPE primlabel_requests_total counter\n"
      "primlabel_requests_total{method=\"Label\",model=\"a\",status=\"OK\"} 5\n"
      "primlabel_requests_total{method=\"Label\",model=\"b\",status=\"OK\"} 2\n"
      "primlabel_requests_total{method=\"Label\",model=\"a\",status=\"UNAVAILABLE\"} 1\n"
      "primlabel_requests_total{method=\"LabelCloud\",model=\"a\",status=\"OK\"} 9\n"
      "primlabel_points_total 100\n";
  const ServerCounts label = parse_server_counts(text, "Label");
  EXPECT_EQ(label.total, 8);
  EXPECT_EQ(label.by_status.at("OK"), 7);
  EXPECT_EQ(parse_server_counts(text, "LabelCloud").total, 9);
  ServerCounts before;
  before.total = 6;
  before.by_status["OK"] = 5;
  before.by_status["UNAVAILABLE"] = 1;
  const ServerCounts delta = label - before;
  EXPECT_EQ(delta.total, 2);
  EXPECT_EQ(delta.by_status.size(), 1u);  // unchanged statuses drop out
  EXPECT_THROW(parse_server_counts("garbage{", "Label"), std::runtime_error);
}

TEST(LoadgenStats, MetricsUrlTakesUrlsAndHostPort) {
  EXPECT_EQ(metrics_url_from("127.0.0.1:9464"), "http://127.0.0.1:9464/metrics");
  EXPECT_EQ(metrics_url_from("labeler:9464"), "http://labeler:9464/metrics");
  EXPECT_EQ(metrics_url_from("http://labeler:9464/metrics"), "http://labeler:9464/metrics");
  EXPECT_EQ(metrics_url_from("https://labeler/prom/metrics"), "https://labeler/prom/metrics");
  // A URL without a path scrapes /metrics, as HOST:PORT does; a path is kept.
  EXPECT_EQ(metrics_url_from("http://127.0.0.1:9464"), "http://127.0.0.1:9464/metrics");
  EXPECT_EQ(metrics_url_from("http://127.0.0.1:9464/"), "http://127.0.0.1:9464/metrics");
  EXPECT_EQ(metrics_url_from("labeler:9464/prom/metrics"), "http://labeler:9464/prom/metrics");
  for (const char* bad : {"", "ftp://labeler/metrics", "file:///etc/passwd", "a b:1", "h:1\n",
                          "http://", "http:///metrics"})
    EXPECT_THROW(metrics_url_from(bad), std::invalid_argument) << bad;
  // Nothing listens on port 1: a clear error, not a hang.
  EXPECT_THROW(read_server_counts("127.0.0.1:1", "Label", 2000), std::runtime_error);
}

std::vector<PointCloud> small_clouds() {
  std::vector<PointCloud> clouds(2);
  for (int c = 0; c < 2; ++c) clouds[c] = test::random_box(300 + 100 * c, 1.0f, c + 1);
  return clouds;
}

client::ClientOptions options_for(const FakeServer& server) {
  client::ClientOptions options;
  options.address = server.address();
  options.retry_attempts = 1;
  return options;
}

// One step over the small clouds against `server`, from a client of its own.
StepResult run_small_step(const FakeServer& server, const LoadSpec& spec) {
  client::Client client(options_for(server));
  return run_step(client, small_clouds(), spec);
}

// `concurrency` callers, each calling again on an answer, until `requests` calls are answered.
LoadSpec closed_loop(int concurrency, std::uint64_t requests) {
  LoadSpec spec;
  spec.concurrency = concurrency;
  spec.requests = requests;
  spec.duration_s = 0;
  return spec;
}

TEST(LoadgenRunner, ClosedLoopSendsExactlyTheRequestCount) {
  FakeServer server;
  const StepResult r = run_small_step(server, closed_loop(3, 20));
  EXPECT_EQ(r.stats.ok(), 20u);
  EXPECT_EQ(r.stats.errors(), 0u);
  EXPECT_EQ(r.stats.points(), 10u * 300 + 10u * 400);
  EXPECT_EQ(server.service.label_calls, 20);
  EXPECT_GT(r.stats.percentile(50), 0.0);
}

TEST(LoadgenRunner, OpenLoopIssuesAtItsRateAndCountsErrorsByStatus) {
  FakeServer server;
  server.service.unavailable_calls = 2;
  LoadSpec spec;
  spec.mode = LoadMode::kOpen;
  spec.rate = 200;
  spec.requests = 12;
  spec.duration_s = 0;
  spec.unary = true;
  const StepResult r = run_small_step(server, spec);
  EXPECT_EQ(r.stats.ok() + r.stats.errors(), 12u);
  EXPECT_EQ(r.stats.errors_by_status().at("UNAVAILABLE"), 2u);
  EXPECT_EQ(server.service.label_calls, 12);
}

// A server at its admission limit answers RESOURCE_EXHAUSTED at once. Callers back off (50 ms
// doubling, capped at 2 s) instead of resending at once: in 1.5 s each caller can make at most
// 1 + 5 calls (50 + 100 + 200 + 400 + 800 ms of backoff, less 20% jitter, fit), where resending
// at once made thousands.
TEST(LoadgenRunner, ClosedLoopBacksOffWhenTheServerRejectsAtAdmission) {
  FakeServer server;
  server.service.exhausted_calls = 1'000'000;
  LoadSpec spec;
  spec.concurrency = 2;
  spec.duration_s = 1.5;
  const StepResult r = run_small_step(server, spec);
  EXPECT_EQ(r.stats.ok(), 0u);
  EXPECT_EQ(r.stats.rejected(), static_cast<std::uint64_t>(server.service.label_calls.load()));
  EXPECT_EQ(r.stats.failed(), 0u);
  EXPECT_GE(server.service.label_calls, 2);
  EXPECT_LE(server.service.label_calls, 2 * 7);
}

TEST(LoadgenRunner, ARejectedCallerResumesOnceTheServerAdmitsAgain) {
  FakeServer server;
  server.service.exhausted_calls = 3;
  const StepResult r = run_small_step(server, closed_loop(1, 10));
  EXPECT_EQ(r.stats.ok(), 7u);
  EXPECT_EQ(r.stats.rejected(), 3u);
  EXPECT_EQ(r.stats.errors(), 3u);
  EXPECT_EQ(r.stats.failed(), 0u);
}

TEST(LoadgenRunner, DurationBoundsAStep) {
  FakeServer server;
  LoadSpec spec;
  spec.duration_s = 0.3;
  const StepResult r = run_small_step(server, spec);
  EXPECT_GT(r.stats.ok(), 0u);
  EXPECT_LT(r.elapsed_s, 30.0);  // bounded, not a timing assertion on the server
}

TEST(LoadgenReport, CsvAndJsonCarryEveryStep) {
  StepResult a;
  a.spec.concurrency = 1;
  a.elapsed_s = 2;
  a.stats.record_ok(0.010, 100);
  a.stats.record_error("UNAVAILABLE");
  StepResult b = a;
  b.spec.concurrency = 3;
  ServerCounts server;
  server.total = 2;
  server.by_status = {{"OK", 1}, {"UNAVAILABLE", 1}};
  const std::vector<ReportRow> rows{{a, server}, {b, std::nullopt}};
  char* buffer = nullptr;
  std::size_t size = 0;
  std::FILE* out = open_memstream(&buffer, &size);
  write_report(out, rows, ReportFormat::kCsv);
  write_report(out, rows, ReportFormat::kJson);
  write_report(out, rows, ReportFormat::kText);
  std::fclose(out);
  const std::string text(buffer, size);
  std::free(buffer);
  EXPECT_NE(text.find("mode,calls,concurrency,rate,elapsed_s,ok,errors"), std::string::npos);
  EXPECT_NE(text.find("closed,stream,1,0,2.000,1,1,0,0.500,50,10.00"), std::string::npos) << text;
  EXPECT_NE(text.find(",UNAVAILABLE=1,2,OK=1;UNAVAILABLE=1,0\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\"latency_ms\":{\"p50\":10.0,"), std::string::npos) << text;
  EXPECT_NE(text.find("\"server\":{\"requests\":2,\"by_status\":{\"OK\":1,\"UNAVAILABLE\":1}}"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("server counted 2 requests (OK 1, UNAVAILABLE 1); loadgen sent 2: match"),
            std::string::npos)
      << text;
}

// The tool against the fake server, which counts its calls on a real /metrics endpoint.
TEST(LoadgenCli, SweepReportsMatchTheServersCounters) {
  auto registry = std::make_shared<prometheus::Registry>();
  prometheus::Exposer exposer("127.0.0.1:0");
  exposer.RegisterCollectable(registry);
  FakeServer server;
  server.service.requests_total = &prometheus::BuildCounter()
                                       .Name("primlabel_requests_total")
                                       .Help("Requests")
                                       .Register(*registry);
  test::TempDir dir;
  write_cloud(dir.file("a.pcd"), test::random_box(500, 1.0f, 3));
  const auto r = test::run_command(
      "( " + test::binary("primlabel-loadgen") + " --server " + server.address() + " " +
      dir.file("a.pcd") + " --requests 7 --concurrency-range 1:3:2 --format csv --metrics-url " +
      "http://127.0.0.1:" + std::to_string(exposer.GetListeningPorts().at(0)) + "/metrics" +
      " 2>/dev/null )");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 3) << r.output;  // header + 2 steps
  EXPECT_NE(r.output.find("closed,stream,1,0,"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("closed,stream,3,0,"), std::string::npos) << r.output;
  EXPECT_EQ(server.service.label_calls, 14);
  // Each step: 7 sent, 7 counted by the server, all OK.
  std::size_t matches = 0;
  for (std::size_t at = 0; (at = r.output.find(",7,OK=7,0\n", at)) != std::string::npos; ++at)
    ++matches;
  EXPECT_EQ(matches, 2u) << r.output;
}

// Rejections at admission are a figure of the report, not a failed run, unless --strict.
TEST(LoadgenCli, RejectionsAreReportedAndFailTheRunOnlyWithStrict) {
  FakeServer server;
  test::TempDir dir;
  write_cloud(dir.file("a.pcd"), test::random_box(200, 1.0f, 4));
  const std::string run = test::binary("primlabel-loadgen") + " --server " + server.address() +
                          " " + dir.file("a.pcd") + " --requests 6";
  server.service.exhausted_calls = 2;
  auto r = test::run_command("( " + run + " --format json 2>/dev/null )");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"ok\":4,\"errors\":2,\"rejected\":2,"), std::string::npos) << r.output;
  server.service.exhausted_calls = 2;
  r = test::run_command("( " + run + " --format csv 2>/dev/null )");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(",server_by_status,rejected\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(",RESOURCE_EXHAUSTED=2,,,2\n"), std::string::npos) << r.output;
  server.service.exhausted_calls = 2;
  r = test::run_command("( " + run + " 2>/dev/null )");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("conc 1: 2 calls rejected at admission (RESOURCE_EXHAUSTED"),
            std::string::npos)
      << r.output;
  server.service.exhausted_calls = 2;
  r = test::run_command("( " + run + " --strict 2>/dev/null )");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  server.service.unavailable_calls = 1;  // another error still fails the run
  r = test::run_command("( " + run + " 2>/dev/null )");
  EXPECT_EQ(r.exit_code, 4) << r.output;
}

// The load generator takes $PRIMLABEL_SERVER like the CLI, and HOST alone means port 50051.
TEST(LoadgenCli, ServerFromTheEnvironmentAndTheDefaultPort) {
  FakeServer server;
  test::TempDir dir;
  write_cloud(dir.file("a.pcd"), test::random_box(100, 1.0f, 5));
  const std::string tool = test::binary("primlabel-loadgen");
  auto r = test::run_command("PRIMLABEL_SERVER=" + server.address() + " " + tool + " " +
                             dir.file("a.pcd") + " --requests 2 --format json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(server.service.label_calls, 2);
  // Whatever listens on 50051 here (or nothing), the address it dials is the default port's.
  r = test::run_command(tool + " --server 127.0.0.1 " + dir.file("a.pcd") +
                        " --requests 1 --deadline 1 --format json");
  EXPECT_NE(r.output.find("points on average, 127.0.0.1:50051"), std::string::npos) << r.output;
}

TEST(LoadgenCli, SynthCloudsOpenLoopJsonAndUsageErrors) {
  FakeServer server;
  const std::string tool = test::binary("primlabel-loadgen");
  const auto r = test::run_command("( " + tool + " --server " + server.address() +
                                   " --synth 1 --max-points 2000 --rate 50 --requests 5 "
                                   "--unary --format json 2>/dev/null )");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"mode\":\"open\",\"calls\":\"unary\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"ok\":5,"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"points_per_s\":"), std::string::npos) << r.output;
  for (const char* args : {"", " --synth 1 --rate 5 --concurrency-range 1:2",
                           " --synth 1 --concurrency-range 5:1", " --synth 1 --duration 0"}) {
    const auto bad = test::run_command(tool + " --server " + server.address() + args);
    EXPECT_EQ(bad.exit_code, 2) << args << ": " << bad.output;  // usage, as every binary
  }
  std::string dead;
  { dead = FakeServer().address(); }
  const auto down = test::run_command(tool + " --server " + dead +
                                      " --synth 1 --max-points 100 --requests 3 2>/dev/null");
  EXPECT_EQ(down.exit_code, 4) << down.output;
  EXPECT_NE(down.output.find("UNAVAILABLE"), std::string::npos) << down.output;
}

}  // namespace
}  // namespace primlabel
