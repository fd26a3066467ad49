// Table I: every method trained and tested on the same described scenes, per descriptor.

#include "primlabel/research/table1.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "primlabel/crf/metrics.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/model/svm_baseline.hpp"
#include "primlabel/pipeline/training.hpp"

namespace primlabel::research {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string format(const char* fmt, auto... args) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, fmt, args...);
  return buffer;
}

void add_paper_figures(Table1Row& row) {
  // Rusu et al. 2009, Table I: only the figures quoted in the issue are filled in.
  if (row.descriptor == "fpfh") row.paper_feature_pts_s = 8173;
  if (row.descriptor == "fpfh" && row.method == "crf") {
    row.paper_test_pts_s = 76997;
    row.paper_accuracy = 0.9736;
  }
  if (row.descriptor == "fpfh" && row.method == "svm") row.paper_accuracy = 0.8967;
}

std::vector<Table1Row> rows_for(const FeatureSettings& features, const std::string& descriptor,
                                const Table1Options& options) {
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  crf::GraphSettings graph;
  const std::vector<std::uint32_t> all_ids = [] {
    std::vector<std::uint32_t> ids;
    for (PrimitiveClass c : all_classes())
      if (c != PrimitiveClass::kUnknown) ids.push_back(class_id(c));
    return ids;
  }();

  const RunContext context{options.threads};  // the report's one thread setting
  std::vector<pipeline::SceneData> train, test;
  double feature_seconds = 0;
  std::size_t described_points = 0;
  auto load = [&](synth::SceneSet set, int count, std::vector<pipeline::SceneData>& out) {
    for (int i = 0; i < count; ++i) {
      PointCloud cloud = synth::synthetic_scene(set, i, options.sensor);
      const std::string source = std::string(synth::set_name(set)) + "#" + std::to_string(i);
      out.push_back(
          pipeline::prepare_scene(std::move(cloud), source, features, graph, all_ids, context));
      feature_seconds += out.back().seconds.descriptors;
      described_points += out.back().truth.size();
      say(format("%s: %s described (%zu points, %.1f s)", descriptor.c_str(), source.c_str(),
                 out.back().truth.size(), out.back().seconds.descriptors));
    }
  };
  load(synth::SceneSet::kTrain, options.train_scenes, train);
  load(synth::SceneSet::kTest, options.test_scenes, test);
  const std::vector<std::uint32_t> class_ids = pipeline::classes_present(train);
  for (auto* set : {&train, &test})
    for (pipeline::SceneData& s : *set) pipeline::assign_labels(s, class_ids);
  std::size_t test_points = 0;
  for (const pipeline::SceneData& s : test) test_points += s.truth.size();
  const double feature_pts_s = double(described_points) / std::max(feature_seconds, 1e-9);

  std::vector<Table1Row> rows;
  for (ModelKind kind : {ModelKind::kCrf, ModelKind::kNodeOnly}) {
    pipeline::ModelTrainingOptions training;
    training.kind = kind;
    training.l2 = options.l2;
    training.iterations = options.iterations;
    training.node_knots = options.node_knots;
    const pipeline::ModelTrainingResult trained =
        pipeline::train_label_model(train, {}, class_ids, features, graph, training, context);
    crf::ConfusionMatrix confusion(class_ids);
    const auto start = std::chrono::steady_clock::now();
    for (const pipeline::SceneData& s : test)
      confusion.add(s.truth, pipeline::predict_scene(trained.model, s, context), 0u);
    const double test_seconds = seconds_since(start);
    Table1Row row{kind == ModelKind::kCrf ? "crf" : "node",
                  descriptor,
                  feature_pts_s,
                  trained.seconds,
                  double(test_points) / std::max(test_seconds, 1e-9),
                  confusion.accuracy()};
    add_paper_figures(row);
    rows.push_back(row);
    say(format("%s+%s: trained in %.1f s, accuracy %.4f", row.method.c_str(), descriptor.c_str(),
               row.train_s, row.accuracy));
  }
  if (options.with_svm) {
    std::vector<crf::LabeledGraph> graphs;
    for (const pipeline::SceneData& s : train) graphs.push_back(s.graph);
    svm::SvmOptions svm_options;
    svm_options.feature_scale = 0.01f;
    auto start = std::chrono::steady_clock::now();
    const svm::SvmClassifier svm = svm::SvmClassifier::train(graphs, class_ids, svm_options);
    const double train_seconds = seconds_since(start);
    crf::ConfusionMatrix confusion(class_ids);
    start = std::chrono::steady_clock::now();
    for (const pipeline::SceneData& s : test)
      confusion.add(s.truth, svm.predict(s.graph.descriptors, 0, options.threads).labels, 0u);
    const double test_seconds = seconds_since(start);
    Table1Row row{"svm",
                  descriptor,
                  feature_pts_s,
                  train_seconds,
                  double(test_points) / std::max(test_seconds, 1e-9),
                  confusion.accuracy()};
    add_paper_figures(row);
    rows.push_back(row);
    say(format("svm+%s: trained in %.1f s, accuracy %.4f", descriptor.c_str(), row.train_s,
               row.accuracy));
  }
  return rows;
}

std::string optional_number(const std::optional<double>& value, const char* fmt) {
  return value ? format(fmt, *value) : std::string("-");
}

}  // namespace

std::vector<Table1Row> run_table1(const Table1Options& options) {
  std::vector<Table1Row> rows = rows_for(options.fpfh, "fpfh", options);
  if (options.with_pfh) {
    FeatureSettings pfh = options.fpfh;
    pfh.descriptor = DescriptorKind::kPfh;
    pfh.features = Neighborhood::Hybrid(options.fpfh.features.radius, options.pfh_max_neighbors);
    for (Table1Row& row : rows_for(pfh, "pfh", options)) rows.push_back(row);
  }
  return rows;
}

std::string table1_text(const std::vector<Table1Row>& rows) {
  std::string out =
      format("%-6s %-5s %14s %10s %14s %9s | %14s %14s %9s\n", "method", "desc", "feature pts/s",
             "train s", "test pts/s", "accuracy", "paper feat/s", "paper test/s", "paper acc");
  for (const Table1Row& r : rows)
    out += format("%-6s %-5s %14.0f %10.2f %14.0f %8.2f%% | %14s %14s %9s\n", r.method.c_str(),
                  r.descriptor.c_str(), r.feature_pts_s, r.train_s, r.test_pts_s, 100 * r.accuracy,
                  optional_number(r.paper_feature_pts_s, "%.0f").c_str(),
                  optional_number(r.paper_test_pts_s, "%.0f").c_str(),
                  r.paper_accuracy ? format("%.2f%%", 100 * *r.paper_accuracy).c_str() : "-");
  return out;
}

std::string table1_json(const std::vector<Table1Row>& rows) {
  std::string out;
  for (const Table1Row& r : rows) {
    const json::Json row = {{"method", r.method},
                            {"descriptor", r.descriptor},
                            {"feature_pts_s", json::rounded(r.feature_pts_s, "%.1f")},
                            {"train_s", json::rounded(r.train_s, "%.3f")},
                            {"test_pts_s", json::rounded(r.test_pts_s, "%.1f")},
                            {"accuracy", json::rounded(r.accuracy, "%.6f")}};
    out += json::dump(row) + "\n";
  }
  return out;
}

}  // namespace primlabel::research
