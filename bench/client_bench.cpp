// primlabel-bench client: where the client's time goes for one frame, as the primlabel CLI
// labels it (client/apps/cli/label_command.cpp): read the file, encode and send the request,
// wait for and decode the answer, write the labeled cloud and its classes JSON. Each client
// stage is printed beside the server's own stage times from the same calls, and what the client
// adds beyond the server's time.
//
//   primlabel-bench client [FILE] [--model MODEL.plm] [--reps N]
//
// Without FILE a synthetic 640x480 Kinect frame (the first held-out scene, with a label and an
// rgba field like the mOSD frames) is written as binary_compressed PCD and read back. Without
// --model the server serves a model with seeded random weights on 7 mm voxels: the client's
// stages do not depend on the model. The server runs in this process on 127.0.0.1 (one job, 2
// OpenMP threads) and is reached over loopback gRPC by primlabel::client::Client, as the CLI
// reaches a server.

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bench_commands.hpp"
#include "common/labeled_output.hpp"
#include "loopback_server_config.hpp"
#include "primlabel/client/client.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/ops/logging.hpp"
#include "primlabel/rpc/label_server.hpp"
#include "primlabel/synth/generate.hpp"
#include "random_label_model.hpp"

namespace {

using namespace primlabel;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

struct Arguments {
  std::string input;  // empty: a synthetic Kinect frame
  std::string model;  // empty: random weights on 7 mm voxels
  int reps = 7;
  int threads = 2;
};

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// What a depth camera's frame file holds: the organised points with a label and a colour.
PointCloud synthetic_kinect_frame() {
  PointCloud frame = synth::synthetic_scene(synth::SceneSet::kTest, 0, synth::SensorKind::kKinect);
  frame.rgba.assign(frame.size(), 0xff808080u);
  return frame;
}

LabelModel random_voxel_model() {
  LabelModel model = testing::random_label_model("bench", "1", 7, 0.5f);
  model.features = FeatureSettings{};
  model.features.voxel_size = 0.007f;  // the served Kinect recipe's voxels
  return model;
}

// One frame through the client, stage by stage (ms), and the server's stages of that call.
struct FrameRun {
  std::map<std::string, double> client;  // read, encode, send, receive, decode, write
  std::map<std::string, double> server;  // the summary's timings
  double call = 0;                       // Client::label, wall
  double end_to_end = 0;                 // read + call + write
  double server_total() const {
    double total = 0;
    for (const auto& [stage, ms] : server) total += ms;
    return total;
  }
  double beyond_server() const { return end_to_end - server_total(); }
};

FrameRun run_frame(client::Client& client, const std::string& model, const std::string& input,
                   const std::string& output) {
  FrameRun run;
  auto start = Clock::now();
  PointCloud cloud = read_cloud(input);
  if (count_finite(cloud) == 0) throw IoError(input + ": no point has finite coordinates");
  run.client["read"] = ms_since(start);

  client::LabelOptions options;
  options.model = model;
  options.scan_id = fs::path(input).stem().string();
  start = Clock::now();
  const client::LabelResult result = client.label(cloud, options);
  run.call = ms_since(start);
  run.client["encode"] = 1e3 * result.client_seconds.encode;
  run.client["send"] = 1e3 * result.client_seconds.send;
  run.client["receive"] = 1e3 * result.client_seconds.receive;
  run.client["decode"] = 1e3 * result.client_seconds.decode;
  for (const v1::StageTiming& t : result.summary.timings())
    run.server[t.stage()] = 1e3 * t.seconds();

  start = Clock::now();
  const PointCloud labeled = client::tools::labeled_cloud(std::move(cloud), result);
  const std::string histogram = client::tools::label_histogram(labeled);
  client::tools::write_labeled_cloud(output, labeled, result);
  run.client["write"] = ms_since(start);
  run.end_to_end = run.client["read"] + run.call + run.client["write"];
  return run;
}

void print_stages(const char* title, const std::vector<std::string>& order,
                  const std::map<std::string, double>& ms) {
  std::printf("%-26s", title);
  for (const std::string& stage : order)
    if (const auto it = ms.find(stage); it != ms.end())
      std::printf(" %s %.2f", stage.c_str(), it->second);
  for (const auto& [stage, value] : ms)  // any stage a newer server adds
    if (std::find(order.begin(), order.end(), stage) == order.end())
      std::printf(" %s %.2f", stage.c_str(), value);
  std::printf("\n");
}

int run_client_bench(const Arguments& args) {
  ops::set_log_level(ops::LogLevel::kWarn);
  const fs::path scratch =
      fs::temp_directory_path() / ("primlabel_client_bench_" + std::to_string(getpid()));
  fs::create_directories(scratch);
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{scratch};

  std::string input = args.input;
  if (input.empty()) {
    input = (scratch / "kinect_frame.pcd").string();
    write_pcd(input, synthetic_kinect_frame(), PcdEncoding::kBinaryCompressed);
  }
  // Served under its own name and version, as a model repository holds it.
  const LabelModel model = args.model.empty() ? random_voxel_model() : load_model(args.model);
  const fs::path model_dir = scratch / "models" / model.name / model.version;
  fs::create_directories(model_dir);
  if (args.model.empty())
    save_model((model_dir / "model.plm").string(), model);
  else
    fs::copy_file(args.model, model_dir / "model.plm");

  ops::ServerConfig config = test::loopback_server_config((scratch / "models").string());
  config.metrics_listen = "";
  config.threads_per_job = args.threads;
  rpc::LabelServer server(config);
  client::ClientOptions client_options;
  client_options.address = "127.0.0.1:" + std::to_string(server.port());
  client::Client client(client_options);

  const std::string output = (scratch / "frame_labeled.pcd").string();
  std::vector<FrameRun> runs;
  for (int rep = -1; rep < args.reps; ++rep) {  // rep -1 warms up the server, the caches and files
    FrameRun run = run_frame(client, model.name, input, output);
    if (rep >= 0) runs.push_back(std::move(run));
  }
  server.shutdown(std::chrono::milliseconds(0));

  // Each stage's best over the reps (the least disturbed by other processes); the server's
  // stages are those of the fastest call, so that they add up.
  std::map<std::string, double> best_client;
  for (const FrameRun& run : runs)
    for (const auto& [stage, ms] : run.client)
      best_client[stage] = std::min(
          best_client.count(stage) ? best_client[stage] : std::numeric_limits<double>::infinity(),
          ms);
  const FrameRun& fastest_call =
      *std::min_element(runs.begin(), runs.end(),
                        [](const FrameRun& a, const FrameRun& b) { return a.call < b.call; });
  std::vector<double> beyond;
  double best_end_to_end = std::numeric_limits<double>::infinity();
  for (const FrameRun& run : runs) {
    beyond.push_back(run.beyond_server());
    best_end_to_end = std::min(best_end_to_end, run.end_to_end);
  }
  std::sort(beyond.begin(), beyond.end());
  const double client_own =
      best_client["read"] + best_client["encode"] + best_client["decode"] + best_client["write"];

  const PointCloud frame = read_cloud(input);
  std::printf("client frame %s: %zu points (%u x %u), %d reps, best of each stage\n",
              fs::path(args.input.empty() ? "synthetic-kinect" : args.input).filename().c_str(),
              frame.size(), frame.width, frame.height, args.reps);
  print_stages("client stages ms:", {"read", "encode", "send", "receive", "decode", "write"},
               best_client);
  print_stages(
      "server stages ms:", {"receive", "prefilter", "normals", "features", "inference", "send"},
      fastest_call.server);
  std::printf("call ms: %.2f = server %.2f + outside the server's stages %.2f\n", fastest_call.call,
              fastest_call.server_total(), fastest_call.call - fastest_call.server_total());
  std::printf(
      "end to end ms: %.2f; beyond the server %.2f best, %.2f median; read + encode + decode + "
      "write %.2f\n",
      best_end_to_end, beyond.front(), beyond[beyond.size() / 2], client_own);

  namespace json = primlabel::json;
  json::Json client_stages = json::Json::object(), server_stages = json::Json::object();
  for (const auto& [stage, ms] : best_client)
    client_stages[stage + "_ms"] = json::rounded(ms, "%.2f");
  for (const auto& [stage, ms] : fastest_call.server)
    server_stages[stage + "_ms"] = json::rounded(ms, "%.2f");
  const json::Json line = {
      {"points", frame.size()},
      {"reps", args.reps},
      {"client_stages", std::move(client_stages)},
      {"server_stages", std::move(server_stages)},
      {"server_total_ms", json::rounded(fastest_call.server_total(), "%.2f")},
      {"call_ms", json::rounded(fastest_call.call, "%.2f")},
      {"end_to_end_ms", json::rounded(best_end_to_end, "%.2f")},
      {"beyond_server_best_ms", json::rounded(beyond.front(), "%.2f")},
      {"beyond_server_median_ms", json::rounded(beyond[beyond.size() / 2], "%.2f")},
      {"client_own_ms", json::rounded(client_own, "%.2f")}};
  std::printf("%s\n", json::dump(line).c_str());
  return 0;
}

}  // namespace

namespace primlabel::bench {

BenchCommand add_client_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "client",
      "The primlabel CLI's own time for one frame (read, encode, send, receive, decode, write) "
      "beside the server's stage times.");
  cmd->add_option("FILE", args->input,
                  "A .pcd or .ply frame (default: a synthetic 640x480 Kinect frame)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--model", args->model,
                  "Model file the server serves (default: random weights on 7 mm voxels)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--reps", args->reps, "Frames timed after one warm-up (best of each stage)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--threads", args->threads, "The server's OpenMP threads per job")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  return {cmd, [args] { return run_client_bench(*args); }};
}

}  // namespace primlabel::bench
