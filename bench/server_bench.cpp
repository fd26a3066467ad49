// primlabel-bench server: the labeling service end to end over loopback gRPC against label_cloud
// in process on the same cloud and model (the server's overhead), and how fast a cancelled
// large request stops computing.
//
//   table : a 22k-point LMS400 table scene (the paper's object + table size)
//   kinect: a 640x480 synthetic Kinect frame (307,200 points, NaN where the ray missed)
//   cancel: a 5M-point request cancelled while it is being labeled, at several moments
//   --frame SENSOR=MODEL or FILE=MODEL (repeatable): the first held-out synthetic scene of that
//     sensor (a 640x480 Kinect frame, a ~87k-point LMS400 scan), or that cloud file (a real frame
//     the model never trained on), labeled with that model file at its own
//     voxel size; prints frames/s, p50 / p90 and per-stage ms (the server's stages from the
//     summary, label_cloud's finer split in process) instead of table / kinect.
//
// label_cloud in process gets the options the server derives from the same request header
// (service/label_options.hpp: the plane cascade on by default), so the labels must match; the
// points the cascade labeled plane are printed (0 for the random model, which recorded no noise).
//
// The model is a CRF with seeded random weights and the default feature settings (the same
// compute as a trained one). One labeling job at a time, 2 OpenMP threads, as the server runs
// on this 2-core machine. Prints one line per figure and a JSON line at the end.

#include <grpcpp/grpcpp.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <stop_token>
#include <thread>

#include "bench_commands.hpp"
#include "label_stages.hpp"
#include "loopback_server_config.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/ops/logging.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/rpc/label_server.hpp"
#include "primlabel/scrape/exposition_parser.hpp"
#include "primlabel/service/label_options.hpp"
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

std::vector<v1::LabelRequest> requests_for(const PointCloud& cloud, std::size_t per_chunk,
                                           const std::string& model = "bench") {
  std::vector<v1::LabelRequest> requests(1);
  v1::ScanHeader& header = *requests[0].mutable_header();
  header.set_model(model);
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

// What the server makes of such a request's header: label_cloud's options in process.
pipeline::LabelingOptions served_options(const PointCloud& cloud, const std::string& model) {
  PointCloud empty;
  empty.viewpoint = cloud.viewpoint;
  return service::labeling_options(requests_for(empty, 1, model).front().header());
}

// One streamed request; returns the labels it got (empty on failure) and, when asked, the
// summary's stage timings.
std::vector<std::uint32_t> label_over_grpc(v1::Labeler::Stub& stub, const PointCloud& cloud,
                                           const std::string& model = "bench",
                                           std::map<std::string, double>* stages = nullptr) {
  grpc::ClientContext context;
  auto stream = stub.Label(&context);
  for (const v1::LabelRequest& request : requests_for(cloud, 87381, model))  // 1 MiB of xyz
    if (!stream->Write(request)) break;
  stream->WritesDone();
  std::vector<std::uint32_t> labels;
  v1::LabelResponse response;
  while (stream->Read(&response)) {
    if (response.has_summary() && stages)
      for (const v1::StageTiming& t : response.summary().timings())
        (*stages)[t.stage()] = 1e3 * t.seconds();
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
  const pipeline::LabelingOptions options = served_options(cloud, "bench");
  std::vector<std::uint32_t> reference;
  for (int rep = -1; rep < reps; ++rep) {  // rep -1 warms both paths up
    PointCloud copy = cloud;
    auto start = Clock::now();
    reference = pipeline::label_cloud(model, copy, options, context).labels;
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

struct FrameFigures {
  std::string name;
  std::size_t points = 0, described = 0, cascaded = 0;
  float voxel = 0;
  double server_p50 = 0, server_p90 = 0, local_p50 = 0, local_p90 = 0;
  std::map<std::string, double> server_stages;               // of the run nearest the server p50
  std::vector<std::pair<std::string, double>> local_stages;  // of the run nearest the local p50
};

std::size_t nearest_to(const std::vector<double>& values, double target) {
  std::size_t best = 0;
  for (std::size_t i = 0; i < values.size(); ++i)
    if (std::abs(values[i] - target) < std::abs(values[best] - target)) best = i;
  return best;
}

// `reps` requests of `cloud` to model `name` over gRPC and as many label_cloud calls in process
// (after one warm-up each), labels compared.
FrameFigures frame_figures(const std::string& label, const std::string& name,
                           const LabelModel& model, const PointCloud& cloud,
                           v1::Labeler::Stub& stub, int reps, int threads) {
  FrameFigures out;
  out.name = label;
  out.points = cloud.size();
  out.voxel = model.features.voxel_size;
  const RunContext context{threads};
  const pipeline::LabelingOptions options = served_options(cloud, name);
  std::vector<double> server_ms, local_ms;
  std::vector<std::map<std::string, double>> server_stages;
  std::vector<pipeline::StageSeconds> local_seconds;
  for (int rep = -1; rep < reps; ++rep) {
    PointCloud copy = cloud;
    auto start = Clock::now();
    pipeline::LabelingResult result = pipeline::label_cloud(model, copy, options, context);
    const double local = ms_since(start);
    std::map<std::string, double> stages;
    start = Clock::now();
    const std::vector<std::uint32_t> labels = label_over_grpc(stub, cloud, name, &stages);
    const double served = ms_since(start);
    if (labels != result.labels)
      std::fprintf(stderr, "%s: labels differ from label_cloud!\n", label.c_str());
    if (rep < 0) continue;
    out.described = result.described_points;
    out.cascaded = result.cascaded_points;
    local_ms.push_back(local);
    local_seconds.push_back(result.seconds);
    server_ms.push_back(served);
    server_stages.push_back(std::move(stages));
  }
  out.server_p50 = percentile(server_ms, 0.5);
  out.server_p90 = percentile(server_ms, 0.9);
  out.local_p50 = percentile(local_ms, 0.5);
  out.local_p90 = percentile(local_ms, 0.9);
  out.server_stages = server_stages[nearest_to(server_ms, out.server_p50)];
  const pipeline::StageSeconds& local = local_seconds[nearest_to(local_ms, out.local_p50)];
  for (const pipeline::LabelingStage& stage : pipeline::kLabelingStages)
    out.local_stages.emplace_back(stage.name, bench::stage_ms(local, stage));

  std::printf(
      "%-24s %7zu points (%6zu described, %6zu of them cascaded, voxel %.3f m): server p50 %7.1f "
      "ms p90 %7.1f ms (%5.2f frames/s) | in-process p50 %7.1f ms p90 %7.1f ms  (%d reps)\n",
      label.c_str(), out.points, out.described, out.cascaded, out.voxel, out.server_p50,
      out.server_p90, 1e3 / out.server_p50, out.local_p50, out.local_p90, reps);
  std::printf("%-24s   server stages ms:", "");
  double staged = 0;
  for (const auto& [stage, ms] : out.server_stages) {
    std::printf(" %s %.1f", stage.c_str(), ms);
    staged += ms;
  }
  // What no stage covers: the client's packing, the transport and the client reading the answer.
  std::printf(" | in no stage %.1f", server_ms[nearest_to(server_ms, out.server_p50)] - staged);
  std::printf("\n%-24s   in-process stages ms:", "");
  for (const auto& [stage, ms] : out.local_stages) std::printf(" %s %.1f", stage.c_str(), ms);
  std::printf("\n");
  std::fflush(stdout);
  return out;
}

double inflight(rpc::LabelServer& server) {
  const std::string text = server.metrics().serialize();
  return scrape::sum_samples(scrape::parse_exposition(text), "primlabel_inflight_requests");
}

// Streams the cloud, cancels `after_ms` after the upload ended, and measures cancel -> request
// slot freed (the worker has stopped computing and the call's reactor is gone).
double cancel_latency(rpc::LabelServer& server, v1::Labeler::Stub& stub,
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

struct Arguments {
  int reps_table = 20, reps_kinect = 5, threads = 2;
  std::size_t cancel_points = 5'000'000;
  bool skip_cancel = false, cancel_only = false;
  std::vector<std::string> frames;  // SENSOR=MODEL
  int reps_frame = 20;
  // When to stop the cancelled request (ms after it started / after the upload ended).
  std::vector<int> cancel_at = {300, 1500, 4000, 8000};
};

int run_server_bench(const Arguments& args) {
  ops::set_log_level(ops::LogLevel::kWarn);
  const fs::path repo = fs::temp_directory_path() / ("primlabel_bench_" + std::to_string(getpid()));
  const LabelModel model = bench_model();
  fs::create_directories(repo / "bench" / "1");
  save_model((repo / "bench" / "1" / "model.plm").string(), model);
  // Each --frame model under its own name (frame0, frame1, ...).
  struct Frame {
    std::string label, name;
    PointCloud cloud;
    LabelModel model;
  };
  std::vector<Frame> frame_cases;
  for (const std::string& spec : args.frames) {
    const std::size_t eq = spec.find('=');
    const std::string input = spec.substr(0, eq);
    const auto sensor = eq == std::string::npos ? std::nullopt : synth::sensor_from_name(input);
    if (eq == std::string::npos || (!sensor && !fs::is_regular_file(input))) {
      std::fprintf(stderr,
                   "primlabel-bench server: usage error: --frame %s: want SENSOR=MODEL or "
                   "FILE=MODEL (an existing cloud file)\n",
                   spec.c_str());
      return primlabel::kExitUsage;
    }
    const std::string file = spec.substr(eq + 1);
    Frame frame{
        fs::path(input).stem().string() + "/" + fs::path(file).stem().string(),
        "frame" + std::to_string(frame_cases.size()),
        sensor ? synth::synthetic_scene(synth::SceneSet::kTest, 0, *sensor) : read_cloud(input),
        load_model(file)};
    fs::create_directories(repo / frame.name / "1");
    fs::copy_file(file, repo / frame.name / "1" / "model.plm");
    frame_cases.push_back(std::move(frame));
  }
  ops::ServerConfig config = test::loopback_server_config(repo.string());
  config.metrics_listen = "";
  config.threads_per_job = args.threads;
  config.max_points = std::max<std::uint64_t>(config.max_points, args.cancel_points);
  rpc::LabelServer server(config);
  grpc::ChannelArguments channel_args;
  channel_args.SetMaxReceiveMessageSize(64 << 20);
  auto stub = v1::Labeler::NewStub(
      grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(server.port()),
                                grpc::InsecureChannelCredentials(), channel_args));

  Latency table, frame;
  PointCloud kinect;
  std::vector<FrameFigures> frame_rows;
  for (const Frame& f : frame_cases)
    frame_rows.push_back(
        frame_figures(f.label, f.name, f.model, f.cloud, *stub, args.reps_frame, args.threads));
  if (!args.cancel_only && frame_cases.empty()) {
    table = compare("table", model, table_scene(22000), *stub, args.reps_table, args.threads);
    kinect = synth::synthetic_scene(synth::SceneSet::kTest, 0, synth::SensorKind::kKinect);
    frame = compare("kinect", model, kinect, *stub, args.reps_kinect, args.threads);
  }

  std::vector<double> cancel_ms, local_stop_ms;
  if (!args.skip_cancel) {
    const PointCloud big = large_surface(args.cancel_points);
    // In process first: stop at several moments, time from request_stop to Cancelled.
    for (int after_ms : args.cancel_at) {
      PointCloud copy = big;
      std::stop_source stop;
      const RunContext context{args.threads, stop.get_token()};
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
    for (int after_ms : args.cancel_at) {
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
  json::Json out = line;
  json::Json rows = json::Json::array();
  for (const FrameFigures& f : frame_rows) {
    json::Json server_stages = json::Json::object(), local_stages = json::Json::object();
    for (const auto& [stage, ms] : f.server_stages)
      server_stages[stage + "_ms"] = json::rounded(ms, "%.2f");
    for (const auto& [stage, ms] : f.local_stages)
      local_stages[stage + "_ms"] = json::rounded(ms, "%.2f");
    rows.push_back({{"frame", f.name},
                    {"points", f.points},
                    {"described", f.described},
                    {"cascaded", f.cascaded},
                    {"voxel_size", json::rounded(f.voxel, "%.4f")},
                    {"server_p50_ms", json::rounded(f.server_p50, "%.2f")},
                    {"server_p90_ms", json::rounded(f.server_p90, "%.2f")},
                    {"frames_per_s", json::rounded(1e3 / f.server_p50, "%.2f")},
                    {"local_p50_ms", json::rounded(f.local_p50, "%.2f")},
                    {"local_p90_ms", json::rounded(f.local_p90, "%.2f")},
                    {"server_stages", std::move(server_stages)},
                    {"local_stages", std::move(local_stages)}});
  }
  if (!frame_rows.empty()) out["frames"] = std::move(rows);
  std::printf("%s\n", json::dump(out).c_str());
  return 0;
}

}  // namespace

namespace primlabel::bench {

BenchCommand add_server_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "server", "End-to-end latency of primlabel-server against label_cloud in process.");
  cmd->add_option("--reps-table", args->reps_table, "repetitions on the 22k table scene")
      ->capture_default_str();
  cmd->add_option("--reps-kinect", args->reps_kinect, "repetitions on the 307k Kinect frame")
      ->capture_default_str();
  cmd->add_option("--threads", args->threads, "OpenMP threads per job")->capture_default_str();
  cmd->add_option("--cancel-points", args->cancel_points, "points of the cancelled request")
      ->capture_default_str();
  cmd->add_option("--frame", args->frames,
                  "SENSOR=MODEL (kinect or lms400; repeatable): the first held-out synthetic "
                  "scene of that sensor labeled with that model file, instead of table / kinect");
  cmd->add_option("--reps-frame", args->reps_frame, "repetitions per --frame")
      ->capture_default_str();
  cmd->add_flag("--skip-cancel", args->skip_cancel, "no cancellation figures");
  cmd->add_flag("--cancel-only", args->cancel_only,
                "only the cancellation figures (no table / kinect)");
  cmd->add_option("--cancel-at", args->cancel_at,
                  "moments (ms) at which the 5M request is cancelled")
      ->capture_default_str();
  return {cmd, [args] { return run_server_bench(*args); }};
}

}  // namespace primlabel::bench
