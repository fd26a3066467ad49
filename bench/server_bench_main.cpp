// primlabel-bench-server: the labeling service end to end over loopback gRPC against label_cloud
// in process on the same cloud and model (the server's overhead), and how fast a cancelled
// large request stops computing.
//
//   table : a 22k-point LMS400 table scene (the paper's object + table size)
//   kinect: a 640x480 synthetic Kinect frame (307,200 points, NaN where the ray missed)
//   cancel: a 5M-point request cancelled while it is being labeled, at several moments
//
// The model is a CRF with seeded random weights and the default feature settings (the same
// compute as a trained one). One labeling job at a time, 2 OpenMP threads, as the server runs
// on this 2-core machine. Prints one line per figure and a JSON line at the end.

#include <grpcpp/grpcpp.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stop_token>
#include <thread>

#include "label_server.hpp"
#include "logging.hpp"
#include "primlabel/build_version.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/scrape/exposition_parser.hpp"
#include "primlabel/synth/generate.hpp"
#include "primlabel/v1/labeling.grpc.pb.h"
#include "primlabel/wire/packing.hpp"
#include "random_label_model.hpp"

namespace {

using namespace primlabel;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  const double rank = p * double(values.size() - 1);
  const std::size_t low = std::size_t(rank);
  const std::size_t high = std::min(values.size() - 1, low + 1);
  return values[low] + (rank - double(low)) * (values[high] - values[low]);
}

LabelModel bench_model() {
  LabelModel model = testing::random_label_model("bench", "1", 7, 0.5f);
  model.features = FeatureSettings{};  // the defaults trained models use
  return model;
}

PointCloud table_scene(std::size_t target) {
  const PointCloud scene =
      synth::synthetic_scene(synth::SceneSet::kTest, 0, synth::SensorKind::kLms400);
  const std::size_t stride = std::max<std::size_t>(1, scene.size() / target);
  PointCloud out;
  out.viewpoint = scene.viewpoint;
  for (std::size_t i = 0; i < scene.size() && out.xyz.size() < target; i += stride)
    out.xyz.push_back(scene.xyz[i]);
  out.width = std::uint32_t(out.xyz.size());
  return out;
}

// A wavy 2236 x 2236 surface at 1 cm spacing: 5M points of normal density.
PointCloud large_surface(std::size_t points) {
  const std::size_t side = std::size_t(std::ceil(std::sqrt(double(points))));
  PointCloud cloud;
  cloud.xyz.reserve(side * side);
  for (std::size_t i = 0; i < side && cloud.xyz.size() < points; ++i)
    for (std::size_t j = 0; j < side && cloud.xyz.size() < points; ++j) {
      const float x = 0.01f * i, y = 0.01f * j;
      cloud.xyz.emplace_back(x, y, 0.05f * std::sin(3.0f * x) * std::cos(2.0f * y));
    }
  cloud.width = std::uint32_t(cloud.xyz.size());
  cloud.viewpoint.origin = Vec3f(0, 0, 5);
  return cloud;
}

std::vector<v1::LabelRequest> requests_for(const PointCloud& cloud, std::size_t per_chunk) {
  std::vector<v1::LabelRequest> requests(1);
  v1::ScanHeader& header = *requests[0].mutable_header();
  header.set_model("bench");
  header.set_scan_id("bench");
  header.set_expected_points(cloud.size());
  header.mutable_viewpoint()->set_x(cloud.viewpoint.origin.x());
  header.mutable_viewpoint()->set_y(cloud.viewpoint.origin.y());
  header.mutable_viewpoint()->set_z(cloud.viewpoint.origin.z());
  for (std::size_t first = 0; first < cloud.size(); first += per_chunk) {
    const std::size_t count = std::min(per_chunk, cloud.size() - first);
    wire::append_le(*requests.emplace_back().mutable_chunk()->mutable_xyz(),
                    std::span<const float>(cloud.xyz[first].data(), 3 * count));
  }
  requests.emplace_back().mutable_end();
  return requests;
}

// One streamed request; returns the labels it got (empty on failure).
std::vector<std::uint32_t> label_over_grpc(v1::Labeler::Stub& stub, const PointCloud& cloud) {
  grpc::ClientContext context;
  auto stream = stub.Label(&context);
  for (const v1::LabelRequest& request : requests_for(cloud, 87381))  // 1 MiB of xyz
    if (!stream->Write(request)) break;
  stream->WritesDone();
  std::vector<std::uint32_t> labels;
  v1::LabelResponse response;
  while (stream->Read(&response)) {
    if (!response.has_chunk()) continue;
    const std::size_t n = labels.size();
    labels.resize(n + response.chunk().labels().size() / 4);
    wire::unpack_le<std::uint32_t>(response.chunk().labels(), labels.data() + n);
  }
  const grpc::Status status = stream->Finish();
  if (!status.ok()) std::fprintf(stderr, "Label failed: %s\n", status.error_message().c_str());
  return status.ok() ? labels : std::vector<std::uint32_t>{};
}

struct Latency {
  std::vector<double> server_ms, local_ms;
};

Latency compare(const char* name, const LabelModel& model, const PointCloud& cloud,
                v1::Labeler::Stub& stub, int reps, int threads) {
  Latency latency;
  const RunContext context{threads};
  std::vector<std::uint32_t> reference;
  for (int rep = -1; rep < reps; ++rep) {  // rep -1 warms both paths up
    PointCloud copy = cloud;
    auto start = Clock::now();
    reference = pipeline::label_cloud(model, copy, {}, context).labels;
    const double local = ms_since(start);
    start = Clock::now();
    const std::vector<std::uint32_t> labels = label_over_grpc(stub, cloud);
    const double served = ms_since(start);
    if (labels != reference) std::fprintf(stderr, "%s: labels differ from label_cloud!\n", name);
    if (rep < 0) continue;
    latency.local_ms.push_back(local);
    latency.server_ms.push_back(served);
  }
  const double p50s = percentile(latency.server_ms, 0.5), p50l = percentile(latency.local_ms, 0.5);
  std::printf(
      "%-7s %8zu points  server p50 %8.1f ms  p99 %8.1f ms | in-process p50 %8.1f ms  p99 %8.1f "
      "ms | overhead p50 %+5.1f%%  (%d reps)\n",
      name, cloud.size(), p50s, percentile(latency.server_ms, 0.99), p50l,
      percentile(latency.local_ms, 0.99), 100.0 * (p50s - p50l) / p50l, reps);
  std::fflush(stdout);
  return latency;
}

double inflight(server::LabelServer& server) {
  const std::string text = server.metrics().serialize();
  return scrape::sum_samples(scrape::parse_exposition(text), "primlabel_inflight_requests");
}

// Streams the cloud, cancels `after_ms` after the upload ended, and measures cancel -> request
// slot freed (the worker has stopped computing and the call's reactor is gone).
double cancel_latency(server::LabelServer& server, v1::Labeler::Stub& stub,
                      const std::vector<v1::LabelRequest>& requests, int after_ms) {
  grpc::ClientContext context;
  auto stream = stub.Label(&context);
  for (const v1::LabelRequest& request : requests)
    if (!stream->Write(request)) break;
  stream->WritesDone();
  std::this_thread::sleep_for(std::chrono::milliseconds(after_ms));
  const auto start = Clock::now();
  context.TryCancel();
  while (inflight(server) > 0 && ms_since(start) < 60000)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const double stopped = ms_since(start);
  stream->Finish();
  return stopped;
}

}  // namespace

int main(int argc, char** argv) {
  int reps_table = 20, reps_kinect = 5, threads = 2;
  std::size_t cancel_points = 5'000'000;
  bool skip_cancel = false, cancel_only = false;
  // When to stop the cancelled request (ms after it started / after the upload ended).
  std::vector<int> cancel_at = {300, 1500, 4000, 8000};
  CLI::App app{"End-to-end latency of primlabel-server against label_cloud in process."};
  app.set_version_flag("--version", primlabel::version_line("primlabel-bench-server"));
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.name("primlabel-bench-server");
  app.add_option("--reps-table", reps_table, "repetitions on the 22k table scene")
      ->capture_default_str();
  app.add_option("--reps-kinect", reps_kinect, "repetitions on the 307k Kinect frame")
      ->capture_default_str();
  app.add_option("--threads", threads, "OpenMP threads per job")->capture_default_str();
  app.add_option("--cancel-points", cancel_points, "points of the cancelled request")
      ->capture_default_str();
  app.add_flag("--skip-cancel", skip_cancel, "no cancellation figures");
  app.add_flag("--cancel-only", cancel_only, "only the cancellation figures (no table / kinect)");
  app.add_option("--cancel-at", cancel_at, "moments (ms) at which the 5M request is cancelled")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "primlabel-bench-server: usage error: %s (see --help)\n", e.what());
    return primlabel::kExitUsage;
  }

  server::set_log_level(server::LogLevel::kWarn);
  const fs::path repo = fs::temp_directory_path() / ("primlabel_bench_" + std::to_string(getpid()));
  const LabelModel model = bench_model();
  fs::create_directories(repo / "bench" / "1");
  save_model((repo / "bench" / "1" / "model.plm").string(), model);
  server::ServerConfig config;
  config.models_dir = repo.string();
  config.listen = "127.0.0.1:0";
  config.metrics_listen = "";
  config.reload_seconds = 0;
  config.workers = 1;
  config.threads_per_job = threads;
  config.max_points = std::max<std::uint64_t>(config.max_points, cancel_points);
  server::LabelServer server(config);
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(64 << 20);
  auto stub = v1::Labeler::NewStub(grpc::CreateCustomChannel(
      "127.0.0.1:" + std::to_string(server.port()), grpc::InsecureChannelCredentials(), args));

  Latency table, frame;
  PointCloud kinect;
  if (!cancel_only) {
    table = compare("table", model, table_scene(22000), *stub, reps_table, threads);
    kinect = synth::synthetic_scene(synth::SceneSet::kTest, 0, synth::SensorKind::kKinect);
    frame = compare("kinect", model, kinect, *stub, reps_kinect, threads);
  }

  std::vector<double> cancel_ms, local_stop_ms;
  if (!skip_cancel) {
    const PointCloud big = large_surface(cancel_points);
    // In process first: stop at several moments, time from request_stop to Cancelled.
    for (int after_ms : cancel_at) {
      PointCloud copy = big;
      std::stop_source stop;
      const RunContext context{threads, stop.get_token()};
      Clock::time_point requested{};
      std::jthread stopper([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(after_ms));
        requested = Clock::now();
        stop.request_stop();
      });
      try {
        pipeline::label_cloud(model, copy, {}, context);
        std::printf("cancel  in-process after %5d ms: finished before the stop\n", after_ms);
      } catch (const pipeline::Cancelled& e) {
        local_stop_ms.push_back(ms_since(requested));
        std::printf("cancel  in-process after %5d ms: stopped %6.1f ms after the request (%s)\n",
                    after_ms, local_stop_ms.back(), e.what());
      }
      std::fflush(stdout);
    }
    const auto requests = requests_for(big, 87381);
    for (int after_ms : cancel_at) {
      cancel_ms.push_back(cancel_latency(server, *stub, requests, after_ms));
      std::printf(
          "cancel  %zu points over gRPC, %5d ms after upload: slot free %6.1f ms after "
          "TryCancel\n",
          big.size(), after_ms, cancel_ms.back());
      std::fflush(stdout);
    }
    std::printf(
        "cancel  over gRPC: slot free p50 %.1f ms, p99 %.1f ms, max %.1f ms (%zu cancels)\n",
        percentile(cancel_ms, 0.5), percentile(cancel_ms, 0.99),
        *std::max_element(cancel_ms.begin(), cancel_ms.end()), cancel_ms.size());
  }
  server.shutdown(std::chrono::milliseconds(0));
  fs::remove_all(repo);

  auto p50 = [](const std::vector<double>& v) { return v.empty() ? 0.0 : percentile(v, 0.5); };
  auto p99 = [](const std::vector<double>& v) { return v.empty() ? 0.0 : percentile(v, 0.99); };
  namespace json = primlabel::json;
  const auto max_of = [](const std::vector<double>& v) {
    return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
  };
  const double overhead = frame.local_ms.empty()
                              ? 0.0
                              : (p50(frame.server_ms) - p50(frame.local_ms)) / p50(frame.local_ms);
  const json::Json line = {{"table_points", std::size_t(22000)},
                           {"table_server_p50_ms", json::rounded(p50(table.server_ms), "%.2f")},
                           {"table_server_p99_ms", json::rounded(p99(table.server_ms), "%.2f")},
                           {"table_local_p50_ms", json::rounded(p50(table.local_ms), "%.2f")},
                           {"kinect_points", kinect.size()},
                           {"kinect_server_p50_ms", json::rounded(p50(frame.server_ms), "%.2f")},
                           {"kinect_server_p99_ms", json::rounded(p99(frame.server_ms), "%.2f")},
                           {"kinect_local_p50_ms", json::rounded(p50(frame.local_ms), "%.2f")},
                           {"kinect_overhead", json::rounded(overhead, "%.4f")},
                           {"cancel_grpc_p99_ms", json::rounded(p99(cancel_ms), "%.1f")},
                           {"cancel_grpc_max_ms", json::rounded(max_of(cancel_ms), "%.1f")},
                           {"cancel_local_max_ms", json::rounded(max_of(local_stop_ms), "%.1f")}};
  std::printf("%s\n", json::dump(line).c_str());
  return 0;
}
