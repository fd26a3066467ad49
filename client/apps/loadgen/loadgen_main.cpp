// primlabel-loadgen: load a primlabel server and report throughput, latency percentiles and
// errors; optionally next to the server's own request counters.
//
//   primlabel-loadgen --server HOST:PORT --synth 2 --concurrency 4 --duration 30
//   primlabel-loadgen --server HOST:PORT scan.pcd --rate 5 --requests 100 --format json
//   primlabel-loadgen --server HOST:PORT --synth 1 --concurrency-range 1:8:2 --format csv

#include <CLI/CLI.hpp>
#include <cstdio>
#include <thread>

#include "common/client_flags.hpp"
#include "load_runner.hpp"
#include "primlabel/build_version.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/synth/generate.hpp"
#include "report.hpp"

using namespace primlabel;
using namespace primlabel::client;
using namespace primlabel::client::loadgen;

namespace {

// The shared scheme (exit_codes.hpp), then the load generator's own codes.
using primlabel::kExitOk;
using primlabel::kExitUsage;
constexpr int kExitInput = primlabel::kExitFailure;  // an input file could not be read
constexpr int kExitMetrics = 3;
constexpr int kExitCallsFailed = 4;

constexpr const char* kFooter =
    "Latency is from sending a cloud to its last label (open loop: from its scheduled send "
    "time). Calls the server rejects at admission (RESOURCE_EXHAUSTED: its workers and queue "
    "full) are a figure of the report, 'rejected'; in the closed loop the caller backs off "
    "(50 ms doubling to 2 s) before its next call. Exit codes: 0 every call succeeded or was "
    "only rejected at admission, 1 an input file could not be read, 2 usage, 3 the "
    "--metrics-url could not be read, 4 some calls failed (the report shows them by status; "
    "with --strict rejections count too).";

PointCloud first_points(PointCloud cloud, std::size_t n) {
  if (n == 0 || n >= cloud.size()) return cloud;
  PointCloud out;
  out.resize_unorganized(n);
  std::copy_n(cloud.xyz.begin(), n, out.xyz.begin());
  out.viewpoint = cloud.viewpoint;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"primlabel-loadgen: load a primlabel server and measure it.", "primlabel-loadgen"};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-loadgen"));
  app.footer(kFooter);
  tools::ConnectionFlags connection;
  connection.retries = 1;  // measure the server, not the client's retries
  connection.add_to(app);
  LoadSpec spec;
  std::vector<std::string> files;
  int synth_count = 0;
  std::string sensor = "lms400", range, format = "text", metrics_url;
  std::size_t max_points = 0;
  bool open_loop = false, strict = false;
  app.add_option("FILE", files, "Clouds to send (.pcd / .ply), in turn");
  app.add_option("--synth", synth_count, "Generate this many synthetic table scenes instead");
  app.add_option("--sensor", sensor, "Synthetic sensor: lms400 | kinect")->capture_default_str();
  app.add_option("--max-points", max_points, "Send only the first N points of each cloud");
  app.add_option("--concurrency", spec.concurrency, "Closed loop: callers")
      ->capture_default_str()
      ->check(CLI::Range(1, 4096));
  app.add_option("--concurrency-range", range, "Sweep START:END:STEP callers, one step each");
  auto* rate = app.add_option("--rate", spec.rate, "Open loop: calls per second");
  app.add_option("--max-outstanding", spec.max_outstanding, "Open loop: calls in flight at most")
      ->capture_default_str();
  app.add_option("--duration", spec.duration_s, "Seconds per step (0 = until --requests)")
      ->capture_default_str();
  app.add_option("--requests", spec.requests, "Calls per step (0 = until --duration)");
  app.add_option("--max-duration", spec.max_duration_s, "Hard cap on a step (s)")
      ->capture_default_str();
  app.add_flag("--unary", spec.unary, "LabelCloud (one message) instead of the Label stream");
  app.add_option("--model", spec.label.model, "Model (default: the server's)");
  app.add_option("--chunk-points", spec.label.chunk_points, "Points per streamed message")
      ->capture_default_str();
  app.add_flag("--descriptors", spec.label.descriptors, "Ask for the descriptors too");
  app.add_flag("--every-point", spec.label.every_point,
               "Describe and infer every point: no plane cascade (slower)");
  app.add_flag("--strict", strict,
               "Exit 4 when the server rejected calls at admission (RESOURCE_EXHAUSTED) too");
  app.add_option("--format", format, "text | csv | json")
      ->capture_default_str()
      ->check(CLI::IsMember({"text", "csv", "json"}));
  app.add_option("--metrics-url", metrics_url,
                 "the server's /metrics, http://HOST:PORT/metrics or HOST:PORT: report its "
                 "primlabel_requests_total delta");
  try {
    app.parse(argc, argv);
    open_loop = rate->count() > 0;
    if (open_loop && !range.empty())
      throw CLI::ValidationError("--concurrency-range sweeps the closed loop; drop --rate");
    if (files.empty() == (synth_count <= 0))
      throw CLI::ValidationError("give cloud files or --synth N (one of them)");
    if (spec.duration_s <= 0 && spec.requests == 0)
      throw CLI::ValidationError("a step needs --duration or --requests");
    if (open_loop && spec.rate <= 0) throw CLI::ValidationError("--rate must be positive");
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "primlabel-loadgen: %s (see --help)\n", e.what());
    return kExitUsage;
  }
  std::vector<int> concurrencies{spec.concurrency};
  if (!range.empty()) {
    try {
      concurrencies = parse_concurrency_range(range);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "primlabel-loadgen: --concurrency-range %s: %s\n", range.c_str(),
                   e.what());
      return kExitUsage;
    }
  }
  if (spec.requests > 0 && app.get_option("--duration")->count() == 0) spec.duration_s = 0;
  spec.mode = open_loop ? LoadMode::kOpen : LoadMode::kClosed;

  std::vector<PointCloud> clouds;
  try {
    for (const auto& f : files) clouds.push_back(first_points(read_cloud(f), max_points));
    for (int i = 0; i < synth_count; ++i) {
      synth::GenerateOptions options;
      options.seed = synth::set_seed(synth::SceneSet::kTest, i);
      const auto kind = synth::sensor_from_name(sensor);
      if (!kind) throw std::runtime_error("unknown sensor '" + sensor + "'");
      options.sensor = *kind;
      clouds.push_back(first_points(synth::generate(options).cloud, max_points));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-loadgen: %s\n", e.what());
    return kExitInput;
  }
  std::size_t total_points = 0;
  for (const auto& c : clouds) total_points += c.size();
  std::fprintf(stderr, "primlabel-loadgen: %zu clouds, %zu points on average, %s\n", clouds.size(),
               total_points / clouds.size(), connection.server.c_str());

  std::unique_ptr<Client> client;
  try {
    client = std::make_unique<Client>(connection.options());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-loadgen: %s\n", e.what());
    return kExitInput;
  }
  const std::string method = spec.unary ? "LabelCloud" : "Label";
  std::vector<ReportRow> rows;
  for (int concurrency : concurrencies) {
    LoadSpec step = spec;
    step.concurrency = concurrency;
    std::optional<ServerCounts> before;
    try {
      if (!metrics_url.empty()) before = read_server_counts(metrics_url, method);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "primlabel-loadgen: %s: %s\n", metrics_url.c_str(), e.what());
      return kExitMetrics;
    }
    if (step.mode == LoadMode::kClosed)
      std::fprintf(stderr, "primlabel-loadgen: concurrency %d ...\n", concurrency);
    else
      std::fprintf(stderr, "primlabel-loadgen: %.1f calls/s ...\n", step.rate);
    ReportRow row{run_step(*client, clouds, step), std::nullopt};
    if (before) {
      // The server counts a call as it finishes it; give the last ones a moment to land.
      const double sent = row.step.stats.ok() + row.step.stats.errors();
      try {
        for (int i = 0; i < 40; ++i) {
          row.server = read_server_counts(metrics_url, method) - *before;
          if (row.server->total >= sent) break;
          std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
      } catch (const std::exception& e) {
        std::fprintf(stderr, "primlabel-loadgen: %s: %s\n", metrics_url.c_str(), e.what());
        return kExitMetrics;
      }
    }
    rows.push_back(std::move(row));
  }
  write_report(stdout, rows,
               format == "csv"    ? ReportFormat::kCsv
               : format == "json" ? ReportFormat::kJson
                                  : ReportFormat::kText);
  for (const auto& row : rows)
    if ((strict ? row.step.stats.errors() : row.step.stats.failed()) > 0) return kExitCallsFailed;
  return kExitOk;
}
