// primlabel-bench-pipeline: points/s of pipeline::label_cloud end to end (normals, FPFH, CRF graph
// and inference) on one held-out synthetic scene per sensor: an LMS400 table scan (~85k points)
// and a Kinect frame (640x480, NaN misses included in the point count). The model is --model, or
// one made here per sensor the way primlabel-train's calibration usually ends: node-only weights
// trained on one training scene plus an associative coupling of 0.25 (loopy BP runs as it would).
// Prints, never asserts; the last line is JSON. With --repeat the fastest run counts.
//
//   primlabel-bench-pipeline --threads 1,2 --repeat 3

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/training.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string model;
  std::vector<std::string> sensors = {"lms400", "kinect"};
  std::vector<int> threads = {2};
  int repeat = 1;
};

struct Row {
  std::string sensor, model;
  int threads = 0;
  std::size_t points = 0, labeled = 0;
  double feature_s = 0, inference_s = 0, total_s = 0;
  double points_per_s() const { return double(points) / std::max(total_s, 1e-9); }
};

LabelModel quick_model(synth::SensorKind sensor) {
  const FeatureSettings features;
  const crf::GraphOptions graph;
  std::vector<std::uint32_t> every_class;
  for (PrimitiveClass c : all_classes()) every_class.push_back(class_id(c));
  std::vector<pipeline::SceneData> train;
  train.push_back(
      pipeline::prepare_scene(pipeline::synthetic_scene(synth::SceneSet::kTrain, 0, sensor),
                              "train", features, graph, every_class, 0));
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

Row measure(const LabelModel& model, const PointCloud& scene, int threads, int repeat) {
  Row best;
  best.total_s = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repeat; ++r) {
    PointCloud cloud = scene;  // label_cloud writes normals into it
    pipeline::LabelingOptions options;
    options.threads = threads;
    const auto start = std::chrono::steady_clock::now();
    const pipeline::LabelingResult result = pipeline::label_cloud(model, cloud, options);
    const double total =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (total < best.total_s) {
      best.total_s = total;
      best.feature_s = result.feature_seconds;
      best.inference_s = result.inference_seconds;
      best.labeled = result.labeled_points;
    }
  }
  best.threads = threads;
  best.points = scene.size();
  return best;
}

int run(const Arguments& args) {
  std::optional<LabelModel> given;
  if (!args.model.empty()) given = load_model(args.model);
  std::vector<Row> rows;
  std::printf("%-7s %-10s %7s %9s %9s %10s %10s %10s %12s\n", "sensor", "model", "threads",
              "points", "labeled", "features s", "infer s", "total s", "points/s");
  for (const std::string& name : args.sensors) {
    const synth::SensorKind sensor = *synth::sensor_from_name(name);
    const PointCloud scene = pipeline::synthetic_scene(synth::SceneSet::kTest, 0, sensor);
    const LabelModel model = given ? *given : quick_model(sensor);
    const std::string model_name =
        given ? "file" : std::string(model.kind == ModelKind::kCrf ? "crf" : "node") + "-quick";
    for (int threads : args.threads) {
      Row row = measure(model, scene, threads, args.repeat);
      row.sensor = name;
      row.model = model_name;
      std::printf("%-7s %-10s %7d %9zu %9zu %10.3f %10.3f %10.3f %12.0f\n", row.sensor.c_str(),
                  row.model.c_str(), row.threads, row.points, row.labeled, row.feature_s,
                  row.inference_s, row.total_s, row.points_per_s());
      std::fflush(stdout);
      rows.push_back(row);
    }
  }
  std::ostringstream json;
  json << "{\"bench\":\"pipeline\",\"rows\":[";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    char buffer[512];
    std::snprintf(buffer, sizeof buffer,
                  "%s{\"sensor\":\"%s\",\"model\":\"%s\",\"threads\":%d,\"points\":%zu,"
                  "\"labeled\":%zu,\"feature_s\":%.4f,\"inference_s\":%.4f,\"total_s\":%.4f,"
                  "\"points_per_s\":%.0f}",
                  i ? "," : "", r.sensor.c_str(), r.model.c_str(), r.threads, r.points, r.labeled,
                  r.feature_s, r.inference_s, r.total_s, r.points_per_s());
    json << buffer;
  }
  json << "]}";
  std::printf("%s\n", json.str().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "End-to-end labeling throughput (label_cloud) on synthetic LMS400 and Kinect scenes."};
  app.name("primlabel-bench-pipeline");
  Arguments args;
  app.add_option("--model", args.model, "model file (default: a quick model per sensor)");
  app.add_option("--sensors", args.sensors, "lms400 and/or kinect (default both)")
      ->delimiter(',')
      ->check(CLI::IsMember({"lms400", "kinect"}));
  app.add_option("--threads", args.threads, "thread counts, e.g. 1,2 (default 2)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  app.add_option("--repeat", args.repeat, "runs per case, the fastest counts (default 1)")
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  try {
    return run(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-bench-pipeline: error: %s\n", e.what());
    return 1;
  }
}
