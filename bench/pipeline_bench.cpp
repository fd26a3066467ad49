// primlabel-bench pipeline: points/s of pipeline::label_cloud end to end (normals, FPFH, CRF graph
// and inference) on one held-out synthetic scene per sensor: an LMS400 table scan (~85k points)
// and a Kinect frame (640x480, NaN misses included in the point count). The model is --model, or
// one made here per sensor the way primlabel-train's calibration usually ends: node-only weights
// trained on one training scene plus an associative coupling of 0.25 (loopy BP runs as it would).
// Prints, never asserts; the last line is JSON. With --repeat: p50 / p90 wall and p50 CPU ms,
// frames/s at the p50, and label_cloud's per-stage ms of the run nearest the p50 (points/s of
// the fastest run, as before).
// With --scans FILE... (and --model) it labels those files instead, each a row named by its file
// (accuracy against its `label` field when it has one): a real frame held out from the model.
// With --stop-latency N it instead stops label_cloud N times at random moments of a run on the
// LMS400 scene and on hostile inputs (100k coincident points, 20k points in a 1 mm cube, both on
// a small table) and prints the p50 / p99 / max time from the stop request to the return.
//
//   primlabel-bench pipeline --threads 1,2 --repeat 3
//   primlabel-bench pipeline --model FOLD.plm --scans learn1_truth.pcd --compare-cascade
//   primlabel-bench pipeline --model kinect.plm --scans kinect-3000.pcd --compare-crease
//   primlabel-bench pipeline --stop-latency 20

#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <stop_token>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bench_commands.hpp"
#include "label_stages.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/synth/generate.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::vector<std::string> models;  // each a set of rows (a release's model beside a new one)
  std::vector<std::string> sensors = {"lms400", "kinect"};
  std::vector<std::string> scans;  // files to label instead of the synthetic scenes
  std::vector<int> threads = {2};
  std::vector<float> voxel_sizes = {-1.0f};  // < 0: the model's own
  int repeat = 1;
  bool compare_unshared = false;  // also each case without the shared neighbour lists
  bool compare_cascade = false;   // also each case with the plane cascade
  bool compare_crease = false;    // also each case with crease_points the other way
  bool tabletop = false;          // only the table and its objects, as `label --tabletop`
  int stop_latency = 0;           // > 0: stops per input
};

// One case: the fastest run's split (feature_s, inference_s) as before, plus the p50 / p90 of the
// wall times and the per-stage ms of the run closest to the p50.
struct Row {
  std::string sensor, model;
  int threads = 0;
  float voxel = 0;
  std::size_t points = 0, labeled = 0, described = 0, cascaded = 0;
  double accuracy = 0;  // share of the scene's labeled points labeled right (NaN: no truth)
  double feature_s = 0, inference_s = 0, total_s = 0;
  double p50_ms = 0, p90_ms = 0;
  double cpu_p50_ms = 0;  // process CPU time (all threads) per run: steadier on a busy machine
  pipeline::StageSeconds stages;  // the p50 run's
  double points_per_s() const { return double(points) / std::max(total_s, 1e-9); }
};

// The share of the scene's points with a true class (not unknown) that `labels` gets right.
double accuracy_against(const PointCloud& scene, const std::vector<std::uint32_t>& labels) {
  if (scene.labels.size() != labels.size()) return std::numeric_limits<double>::quiet_NaN();
  const std::uint32_t unknown = class_id(PrimitiveClass::kUnknown);
  std::size_t scored = 0, right = 0;
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (scene.labels[i] != unknown) ++scored, right += labels[i] == scene.labels[i] ? 1 : 0;
  return scored ? double(right) / double(scored) : std::numeric_limits<double>::quiet_NaN();
}

// CPU time of the whole process so far (user + system, all threads), ms.
double process_cpu_ms() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto ms = [](const timeval& t) {
    return 1e3 * double(t.tv_sec) + 1e-3 * double(t.tv_usec);
  };
  return ms(usage.ru_utime) + ms(usage.ru_stime);
}

double percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  const double rank = p * double(values.size() - 1);
  const std::size_t low = std::size_t(rank);
  const std::size_t high = std::min(values.size() - 1, low + 1);
  return values[low] + (rank - double(low)) * (values[high] - values[low]);
}

LabelModel quick_model(synth::SensorKind sensor) {
  const FeatureSettings features;
  const crf::GraphSettings graph;
  std::vector<std::uint32_t> every_class;
  for (PrimitiveClass c : all_classes()) every_class.push_back(class_id(c));
  std::vector<pipeline::SceneData> train;
  train.push_back(
      pipeline::prepare_scene(synth::synthetic_scene(synth::SceneSet::kTrain, 0, sensor), "train",
                              features, graph, every_class));
  const auto class_ids = pipeline::classes_present(train);
  pipeline::assign_labels(train.front(), class_ids);
  pipeline::ModelTrainingOptions options;
  options.kind = ModelKind::kNodeOnly;
  options.iterations = 50;
  LabelModel model =
      pipeline::train_label_model(train, {}, class_ids, features, graph, options).model;
  model.kind = ModelKind::kCrf;
  crf::CrfModel& w = model.weights;
  w.edge_weights = Eigen::MatrixXf::Zero(w.num_classes(), w.edge_feature_dim());
  w.edge_weights.col(w.edge_feature_dim() - 1).setConstant(0.25f);
  return model;
}

Row measure(const LabelModel& model, const PointCloud& scene, int threads, int repeat, float voxel,
            bool share_lists, bool cascade, bool crease, bool tabletop) {
  Row best;
  best.total_s = std::numeric_limits<double>::infinity();
  pipeline::LabelingOptions options;
  if (voxel >= 0.0f) options.voxel_size = voxel;
  options.share_neighbor_lists = share_lists;
  options.plane_cascade = cascade;
  options.crease_points = crease;
  options.tabletop_only = options.want_objects = tabletop;
  std::vector<double> totals, cpu;
  std::vector<pipeline::StageSeconds> runs;
  for (int r = 0; r < repeat; ++r) {
    PointCloud cloud = scene;  // label_cloud writes normals into it
    const double cpu_start = process_cpu_ms();
    const auto start = std::chrono::steady_clock::now();
    pipeline::LabelingResult result =
        pipeline::label_cloud(model, cloud, options, RunContext{threads});
    cpu.push_back(process_cpu_ms() - cpu_start);
    const double total =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    totals.push_back(total);
    if (total < best.total_s) {
      best.total_s = total;
      best.feature_s = result.seconds.normals + result.seconds.descriptors;
      best.inference_s = result.seconds.graph + result.seconds.inference;
      best.labeled = result.labeled_points;
      best.described = result.described_points;
      best.cascaded = result.cascaded_points;
      best.accuracy = accuracy_against(scene, result.labels);
    }
    runs.push_back(result.seconds);
  }
  best.p50_ms = 1e3 * percentile(totals, 0.5);
  best.p90_ms = 1e3 * percentile(totals, 0.9);
  best.cpu_p50_ms = percentile(cpu, 0.5);
  // The run closest to the p50 gives the split.
  std::size_t median = 0;
  for (std::size_t r = 0; r < totals.size(); ++r)
    if (std::abs(1e3 * totals[r] - best.p50_ms) < std::abs(1e3 * totals[median] - best.p50_ms))
      median = r;
  best.stages = runs[median];
  best.threads = threads;
  best.voxel = voxel >= 0.0f ? voxel : model.features.voxel_size;
  best.points = scene.size();
  return best;
}

// A small table (2,500 points, 1 cm apart, z = 0) plus `extra`.
PointCloud table_with(const std::vector<Vec3f>& extra) {
  PointCloud cloud;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 50; ++j) cloud.xyz.emplace_back(i * 0.01f, j * 0.01f, 0.0f);
  cloud.xyz.insert(cloud.xyz.end(), extra.begin(), extra.end());
  cloud.width = static_cast<std::uint32_t>(cloud.xyz.size());
  cloud.viewpoint.origin = Vec3f(0.25f, 0.25f, 1.0f);
  return cloud;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Stop latencies (ms) of `stops` runs, each stopped at a uniformly random moment of a full run.
std::vector<double> stop_latencies(const LabelModel& model, const PointCloud& input, int threads,
                                   int stops, double& full_s) {
  {
    PointCloud cloud = input;
    const auto start = std::chrono::steady_clock::now();
    pipeline::label_cloud(model, cloud, {}, RunContext{threads});
    full_s = seconds_since(start);
  }
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> moment(0.0, full_s);
  std::vector<double> latencies;
  for (int s = 0; s < stops; ++s) {
    PointCloud cloud = input;
    std::stop_source source;
    const RunContext context{threads, source.get_token()};
    const double at = moment(rng);
    std::chrono::steady_clock::time_point stopped{};
    std::jthread stopper([&] {
      std::this_thread::sleep_for(std::chrono::duration<double>(at));
      stopped = std::chrono::steady_clock::now();
      source.request_stop();
    });
    bool cancelled = false;
    try {
      pipeline::label_cloud(model, cloud, {}, context);
    } catch (const Cancelled&) {
      cancelled = true;
    }
    const auto returned = std::chrono::steady_clock::now();
    stopper.join();
    if (cancelled)
      latencies.push_back(std::chrono::duration<double, std::milli>(returned - stopped).count());
  }
  std::sort(latencies.begin(), latencies.end());
  return latencies;
}

int run_stop_latency(const Arguments& args) {
  const PointCloud scene =
      synth::synthetic_scene(synth::SceneSet::kTest, 0, synth::SensorKind::kLms400);
  const LabelModel model = args.models.empty() ? quick_model(synth::SensorKind::kLms400)
                                               : load_model(args.models.front());
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> mm(0.0f, 0.001f);
  std::vector<Vec3f> cube(20000);
  for (Vec3f& p : cube) p = Vec3f(0.2f + mm(rng), 0.2f + mm(rng), mm(rng));
  const std::vector<std::pair<std::string, PointCloud>> inputs = {
      {"lms400-scene", scene},
      {"coincident-100k", table_with(std::vector<Vec3f>(100000, Vec3f(0.2f, 0.2f, 0.0f)))},
      {"cube-1mm-20k", table_with(cube)}};
  const int threads = args.threads.front();
  std::printf("%-16s %8s %9s %6s %9s %9s %9s\n", "input", "points", "full s", "stops", "p50 ms",
              "p99 ms", "max ms");
  namespace json = primlabel::json;
  json::Json rows = json::Json::array();
  for (const auto& [name, cloud] : inputs) {
    double full_s = 0;
    const std::vector<double> ms = stop_latencies(model, cloud, threads, args.stop_latency, full_s);
    const auto at = [&](double q) {
      return ms.empty() ? 0.0 : ms[std::min(ms.size() - 1, std::size_t(q * double(ms.size())))];
    };
    std::printf("%-16s %8zu %9.3f %6zu %9.1f %9.1f %9.1f\n", name.c_str(), cloud.size(), full_s,
                ms.size(), at(0.5), at(0.99), ms.empty() ? 0.0 : ms.back());
    std::fflush(stdout);
    rows.push_back({{"input", name},
                    {"points", cloud.size()},
                    {"full_s", json::rounded(full_s, "%.3f")},
                    {"stops", ms.size()},
                    {"p50_ms", json::rounded(at(0.5), "%.2f")},
                    {"p99_ms", json::rounded(at(0.99), "%.2f")},
                    {"max_ms", json::rounded(ms.empty() ? 0.0 : ms.back(), "%.2f")}});
  }
  const json::Json line = {
      {"bench", "stop_latency"}, {"threads", threads}, {"rows", std::move(rows)}};
  std::printf("%s\n", json::dump(line).c_str());
  return 0;
}

int run_pipeline_bench(const Arguments& args) {
  if (args.stop_latency > 0) return run_stop_latency(args);
  if (!args.scans.empty() && args.models.empty())
    throw cli::UsageError("--scans needs --model (a held-out file needs a model to label it)");
  // (row name, model); none given: a quick model per sensor, made below.
  std::vector<std::pair<std::string, LabelModel>> given;
  for (const std::string& path : args.models)
    given.emplace_back(std::filesystem::path(path).stem().string(), load_model(path));
  std::vector<Row> rows;
  std::printf("%-7s %-18s %3s %6s %8s %8s %8s %8s %8s %7s %8s %6s", "sensor", "model", "thr",
              "voxel", "points", "voxels", "cascaded", "p50 ms", "p90 ms", "frame/s", "cpu ms",
              "acc %");
  // Per case the default first, then the comparisons asked for.
  struct Variant {
    bool share, cascade, crease;
  };
  const bool crease = pipeline::LabelingOptions{}.crease_points;
  std::vector<Variant> variants = {{true, false, crease}};
  if (args.compare_unshared) variants.insert(variants.begin(), {false, false, crease});
  if (args.compare_cascade) variants.push_back({true, true, crease});
  if (args.compare_crease) variants.push_back({true, false, !crease});
  for (const pipeline::LabelingStage& c : pipeline::kLabelingStages)
    std::printf(" %*s", bench::stage_column_width(c), c.name);
  std::printf("\n");
  // (row name, scene): the files asked for, else one synthetic test scene per sensor.
  std::vector<std::pair<std::string, PointCloud>> scenes;
  for (const std::string& path : args.scans) {
    PointCloud scene = read_cloud(path);
    if (scene.has_labels()) scene = load_labeled_cloud(path);  // the labels as class ids
    scenes.emplace_back(std::filesystem::path(path).stem().string(), std::move(scene));
  }
  if (args.scans.empty())
    for (const std::string& name : args.sensors)
      scenes.emplace_back(
          name, synth::synthetic_scene(synth::SceneSet::kTest, 0, *synth::sensor_from_name(name)));
  for (const auto& [name, scene] : scenes) {
    std::vector<std::pair<std::string, LabelModel>> models = given;
    if (models.empty()) {
      LabelModel quick = quick_model(*synth::sensor_from_name(name));
      const std::string quick_name =
          std::string(quick.kind == ModelKind::kCrf ? "crf" : "node") + "-quick";
      models.emplace_back(quick_name, std::move(quick));
    }
    for (const auto& [model_name, model] : models)
      for (float voxel : args.voxel_sizes)
        for (int threads : args.threads)
          for (const Variant& v : variants) {
            Row row = measure(model, scene, threads, args.repeat, voxel, v.share, v.cascade,
                              v.crease, args.tabletop);
            row.sensor = name;
            row.model = model_name + (v.share ? "" : "-unshared") + (v.cascade ? "-cascade" : "") +
                        (v.crease == crease ? ""
                         : v.crease         ? "-crease"
                                            : "-nocrease");
            std::printf("%-7s %-18s %3d %6.3f %8zu %8zu %8zu %8.1f %8.1f %7.2f %8.1f %6.2f",
                        row.sensor.c_str(), row.model.c_str(), row.threads, row.voxel, row.points,
                        row.described, row.cascaded, row.p50_ms, row.p90_ms, 1e3 / row.p50_ms,
                        row.cpu_p50_ms, 100 * row.accuracy);
            for (const pipeline::LabelingStage& c : pipeline::kLabelingStages)
              std::printf(" %*.1f", bench::stage_column_width(c), bench::stage_ms(row.stages, c));
            std::printf("\n");
            std::fflush(stdout);
            rows.push_back(std::move(row));
          }
  }
  namespace json = primlabel::json;
  json::Json out_rows = json::Json::array();
  for (const Row& r : rows) {
    json::Json stages = json::Json::object();
    for (const pipeline::LabelingStage& c : pipeline::kLabelingStages)
      stages[std::string(c.name) + "_ms"] = json::rounded(bench::stage_ms(r.stages, c), "%.2f");
    out_rows.push_back({{"sensor", r.sensor},
                        {"model", r.model},
                        {"threads", r.threads},
                        {"voxel_size", json::rounded(r.voxel, "%.4f")},
                        {"points", r.points},
                        {"described", r.described},
                        {"labeled", r.labeled},
                        {"cascaded", r.cascaded},
                        {"accuracy", json::rounded(r.accuracy, "%.5f")},
                        {"feature_s", json::rounded(r.feature_s, "%.4f")},
                        {"inference_s", json::rounded(r.inference_s, "%.4f")},
                        {"total_s", json::rounded(r.total_s, "%.4f")},
                        {"p50_ms", json::rounded(r.p50_ms, "%.2f")},
                        {"p90_ms", json::rounded(r.p90_ms, "%.2f")},
                        {"frames_per_s", json::rounded(1e3 / r.p50_ms, "%.2f")},
                        {"cpu_p50_ms", json::rounded(r.cpu_p50_ms, "%.2f")},
                        {"points_per_s", json::whole(r.points_per_s())},
                        {"stages", std::move(stages)}});
  }
  const json::Json line = {{"bench", "pipeline"}, {"rows", std::move(out_rows)}};
  std::printf("%s\n", json::dump(line).c_str());
  return 0;
}

}  // namespace

namespace primlabel::bench {

BenchCommand add_pipeline_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "pipeline",
      "End-to-end labeling throughput (label_cloud) on synthetic LMS400 and Kinect scenes.");
  cmd->add_option("--model", args->models,
                  "model files, each its rows in the same run (a release's beside a new one; "
                  "default: a quick model per sensor)")
      ->delimiter(',')
      ->check(CLI::ExistingFile);
  cmd->add_option("--scans", args->scans,
                  "label these files instead (needs --model; accuracy from their label field)")
      ->delimiter(',')
      ->check(CLI::ExistingFile);
  cmd->add_option("--sensors", args->sensors, "lms400 and/or kinect (default both)")
      ->delimiter(',')
      ->check(CLI::IsMember({"lms400", "kinect"}));
  cmd->add_option("--threads", args->threads, "thread counts, e.g. 1,2 (default 2)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  cmd->add_option("--voxel-size", args->voxel_sizes,
                  "voxel sizes (m), e.g. 0,0.005; 0 = full resolution (default: the model's own)")
      ->delimiter(',');
  cmd->add_flag("--compare-unshared", args->compare_unshared,
                "also run every case with each stage searching itself (no shared neighbour lists)");
  cmd->add_flag("--compare-cascade", args->compare_cascade,
                "also run every case with the plane cascade (LabelingOptions::plane_cascade)");
  cmd->add_flag("--compare-crease", args->compare_crease,
                "also run every case with LabelingOptions::crease_points the other way (the "
                "per-point labels near creases)");
  cmd->add_flag("--tabletop", args->tabletop,
                "label only the table and the objects on it, with the objects (as the service's "
                "label --tabletop --objects)");
  cmd->add_option("--repeat", args->repeat, "runs per case, the fastest counts (default 1)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--stop-latency", args->stop_latency,
                  "instead: stop this many runs per input at random moments, print the latency")
      ->check(CLI::PositiveNumber);
  return {cmd, [args] { return run_pipeline_bench(*args); }};
}

}  // namespace primlabel::bench
