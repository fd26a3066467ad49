// primlabel-eval: labels clouds with a trained model and scores them against their ground truth,
// or re-measures the paper's Table I and Fig. 4.
//
//   primlabel-eval --model table.plm scene.pcd [--json] [--out labeled.pcd]
//   primlabel-eval --model table.plm scene.pcd --primitives scene_primitives.json  # instances
//   primlabel-eval --model table.plm --no-truth mosd_scene.pcd     # predicted label histogram
//   primlabel-eval --model table.plm --confusion-png confusion.png a.pcd b.pcd   # over all files
//   primlabel-eval --table1 [--json]
//   primlabel-eval --fig4 out/ [--fig4-scenes 3]                    # the paper's Fig. 4
//   primlabel-eval --model kinect.plm --mosd-report out/ ../shared/data/mosd/*.pcd
//   primlabel-eval --calibrate-kinect ../shared/data/mosd [--calibration-json out.json]
//   primlabel-eval --model kinect.plm --mosd-report out/ --object-truth [--write-truth t/] scenes
//   primlabel-eval --write-truth truth/ ../shared/data/mosd/*.pcd     # the fitted truth only
//   primlabel-eval --truth-check 4                                   # its error on synthetic

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "node_basis.hpp"
#include "primlabel/build_version.hpp"
#include "primlabel/cli/cli_common.hpp"
#include "primlabel/crf/metrics.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/primitives/primitives_json.hpp"
#include "primlabel/research/confusion_plot.hpp"
#include "primlabel/research/fig4.hpp"
#include "primlabel/research/kinect_calibration.hpp"
#include "primlabel/research/mosd_report.hpp"
#include "primlabel/research/table1.hpp"
#include "primlabel/research/truth_check.hpp"
#include "primlabel/tabletop/objects_json.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string model, classes, out, primitives_json, objects_json, confusion_png, fig4_dir, mosd_dir,
      truth_dir, calibrate_dir, calibration_json;
  std::vector<std::string> files;
  bool json = false, no_truth = false, tabletop_only = false, quiet = false;
  bool table1 = false, no_pfh = false, no_svm = false, object_truth = false, fit_simulation = false;
  int truth_check = 0;
  double truth_radius = research::ObjectTruthOptions{}.label_radius;
  std::string node_basis = "tent";
  std::vector<float> node_knots;  // --node-knots, then the resolved basis (cli::node_knots)
  int table1_train = 8, table1_test = 4, pfh_max_neighbors = 40, threads = 0, fig4_scenes = 3;
};

std::string class_name(std::uint32_t id) {
  const auto c = class_from_id(id);
  return c ? std::string(name(*c)) : std::to_string(id);
}

// Scores at the 6 decimals the JSON lines have always carried; null when undefined (NaN).
json::Json score(double value) { return json::rounded(value, "%.6f"); }

void print_scores(const std::string& path, const crf::ConfusionMatrix& confusion, bool as_json) {
  std::vector<std::string> names;
  for (std::uint32_t id : confusion.class_ids()) names.push_back(class_name(id));
  if (!as_json) {
    std::printf("%s: %llu points scored, accuracy %.2f%%\n%s\n", path.c_str(),
                static_cast<unsigned long long>(confusion.total()), 100 * confusion.accuracy(),
                confusion.to_text(names).c_str());
    return;
  }
  json::Json classes = json::Json::object();
  for (int k = 0; k < confusion.num_classes(); ++k) {
    const crf::ClassScores s = confusion.scores(k);
    classes[names[k]] = {{"precision", score(s.precision)},
                         {"recall", score(s.recall)},
                         {"f1", score(s.f1)},
                         {"support", s.support}};
  }
  json::Json matrix = json::Json::array();
  for (int t = 0; t < confusion.num_classes(); ++t) {
    json::Json row = json::Json::array();
    for (int p = 0; p <= confusion.num_classes(); ++p) row.push_back(confusion.count(t, p));
    matrix.push_back(std::move(row));
  }
  const json::Json line = {{"file", path},
                           {"points", confusion.total()},
                           {"accuracy", score(confusion.accuracy())},
                           {"macro_f1", score(confusion.macro_f1())},
                           {"classes", std::move(classes)},
                           {"confusion", std::move(matrix)}};
  std::printf("%s\n", json::dump(line).c_str());
}

void print_histogram(const std::string& path, const std::vector<std::uint32_t>& labels,
                     bool as_json) {
  std::vector<std::uint64_t> counts(kPrimitiveClassCount, 0);
  for (std::uint32_t id : labels)
    if (id < kPrimitiveClassCount) ++counts[id];
  if (as_json) {
    json::Json histogram = json::Json::object();
    for (std::uint32_t id = 0; id < kPrimitiveClassCount; ++id)
      histogram[class_name(id)] = counts[id];
    const json::Json line = {
        {"file", path}, {"points", labels.size()}, {"histogram", std::move(histogram)}};
    std::printf("%s\n", json::dump(line).c_str());
    return;
  }
  std::printf("%s: %zu points, predicted labels:\n", path.c_str(), labels.size());
  for (std::uint32_t id = 0; id < kPrimitiveClassCount; ++id)
    if (counts[id])
      std::printf("  %-18s %10llu  %6.2f%%\n", class_name(id).c_str(),
                  static_cast<unsigned long long>(counts[id]),
                  100.0 * double(counts[id]) / double(std::max<std::size_t>(labels.size(), 1)));
}

int evaluate_files(const Arguments& args) {
  const LabelModel model = load_model(args.model);
  const ClassMap map = args.classes.empty() ? ClassMap{} : read_class_map(args.classes);
  crf::ConfusionMatrix overall(model.class_ids());  // every scored file, for the PNG
  for (const std::string& path : args.files) {
    PointCloud cloud = read_cloud(path);
    const bool scored = !args.no_truth && cloud.has_labels();
    if (scored)  // the labels as taxonomy ids (through the file's or the given class map)
      cloud = args.classes.empty() ? load_labeled_cloud(path) : load_labeled_cloud(path, map);
    pipeline::LabelingOptions options;
    options.tabletop_only = args.tabletop_only;
    options.want_primitives = !args.primitives_json.empty();
    options.want_objects = !args.objects_json.empty();
    const pipeline::LabelingResult result =
        pipeline::label_cloud(model, cloud, options, RunContext{args.threads});
    if (result.primitives) {
      const auto& instances = result.primitives->primitives;
      atomic_write_file(args.primitives_json, primitives::primitives_json(instances));
      if (!args.quiet)
        std::fprintf(stderr, "%s: %zu primitives in %.3f s, wrote %s\n", path.c_str(),
                     instances.size(), result.seconds.primitives, args.primitives_json.c_str());
    }
    if (result.objects) {
      atomic_write_file(args.objects_json, tabletop::objects_json(*result.objects));
      if (!args.quiet)
        std::fprintf(stderr, "%s: %zu table-top objects, wrote %s\n", path.c_str(),
                     result.objects->objects.size(), args.objects_json.c_str());
    }
    if (!args.quiet)
      std::fprintf(stderr, "%s: %zu points, features %.2f s, inference %.2f s\n", path.c_str(),
                   cloud.size(), result.seconds.normals + result.seconds.descriptors,
                   result.seconds.graph + result.seconds.inference);
    if (!result.domain_warning.empty())
      std::fprintf(stderr, "primlabel-eval: warning: %s: %s\n", path.c_str(),
                   result.domain_warning.c_str());
    if (scored) {
      crf::ConfusionMatrix confusion(model.class_ids());
      confusion.add(cloud.labels, result.labels, class_id(PrimitiveClass::kUnknown));
      print_scores(path, confusion, args.json);
      overall.add(confusion);
    } else {
      print_histogram(path, result.labels, args.json);
    }
    if (!args.out.empty()) {
      cloud.labels = result.labels;
      write_tagged_cloud(args.out, cloud,
                         {{"classes", class_map_tag(ClassMap::taxonomy())},
                          {"model", model.name},
                          {"model_version", model.version},
                          {"descriptor", model.features.descriptor_name()}});
    }
  }
  if (!args.confusion_png.empty()) {
    if (overall.total() == 0)
      throw std::runtime_error("--confusion-png: no file had ground-truth primitive labels");
    std::vector<std::string> names;
    for (std::uint32_t id : overall.class_ids()) names.push_back(class_name(id));
    research::write_confusion_png(
        args.confusion_png, overall, names,
        args.files.size() == 1 ? args.files.front() : std::to_string(args.files.size()) + " files");
  }
  return cli::kExitOk;
}

int table1(const Arguments& args) {
  research::Table1Options options;
  options.train_scenes = args.table1_train;
  options.test_scenes = args.table1_test;
  options.with_pfh = !args.no_pfh;
  options.with_svm = !args.no_svm;
  options.pfh_max_neighbors = args.pfh_max_neighbors;
  options.node_knots = args.node_knots;
  options.threads = args.threads;
  if (!args.quiet)
    options.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const auto rows = research::run_table1(options);
  std::fputs((args.json ? research::table1_json(rows) : research::table1_text(rows)).c_str(),
             stdout);
  return cli::kExitOk;
}

void make_directory(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot be created (" + ec.message() + ")");
}

research::MosdTruthRequest truth_request(const Arguments& args, const std::string& scene) {
  research::MosdTruthRequest request;
  request.enabled = args.object_truth || !args.truth_dir.empty();
  request.options.label_radius = args.truth_radius;
  if (!args.truth_dir.empty())
    request.write_path = (std::filesystem::path(args.truth_dir) /
                          (std::filesystem::path(scene).stem().string() + "_truth.pcd"))
                             .string();
  return request;
}

// The fitted object truth of mOSD scenes alone: a labeled PCD per scene and truth_fits.json.
int write_truth(const Arguments& args) {
  make_directory(args.truth_dir);
  json::Json scenes = json::Json::array();
  research::MosdObjectTruth all;
  for (const std::string& path : args.files) {
    const PointCloud cloud = read_cloud(path);
    research::MosdObjectTruth t;
    try {
      t = research::fit_mosd_truth(cloud, truth_request(args, path), RunContext{args.threads});
    } catch (const std::exception& e) {
      throw std::runtime_error(path + ": " + e.what());
    }
    std::printf(
        "%s: %zu segments: %zu box, %zu upright cylinder, %zu lying cylinder, %zu "
        "unfitted; %llu of %llu object points labeled; wrote %s\n",
        path.c_str(), t.objects.size(), t.count(research::FittedKind::kBox),
        t.count(research::FittedKind::kUprightCylinder),
        t.count(research::FittedKind::kLyingCylinder), t.count(research::FittedKind::kUnfitted),
        static_cast<unsigned long long>(t.truth_points),
        static_cast<unsigned long long>(t.object_points), t.truth_file.c_str());
    json::Json scene = research::object_truth_json(t, true);
    scene["file"] = path;
    scenes.push_back(std::move(scene));
    all.objects.insert(all.objects.end(), t.objects.begin(), t.objects.end());
    all.object_points += t.object_points;
    all.truth_points += t.truth_points;
  }
  const json::Json out = {{"scenes", std::move(scenes)},
                          {"overall", research::object_truth_json(all, false)}};
  atomic_write_file((std::filesystem::path(args.truth_dir) / "truth_fits.json").string(),
                    json::dump(out) + "\n");
  return cli::kExitOk;
}

int truth_check(const Arguments& args) {
  research::TruthCheckOptions options;
  options.scenes = args.truth_check;
  options.truth.label_radius = args.truth_radius;
  const research::TruthCheck check =
      research::check_truth_on_synthetic(options, RunContext{args.threads});
  std::fputs(
      (args.json ? research::truth_check_json(check) : research::truth_check_text(check)).c_str(),
      stdout);
  return cli::kExitOk;
}

int mosd_report(const Arguments& args) {
  const LabelModel model = load_model(args.model);
  make_directory(args.mosd_dir);
  if (!args.truth_dir.empty()) make_directory(args.truth_dir);
  pipeline::LabelingOptions options;
  options.tabletop_only = args.tabletop_only;
  const RunContext context{args.threads};
  std::vector<research::MosdSceneReport> scenes;
  for (const std::string& path : args.files) {
    const std::string png = (std::filesystem::path(args.mosd_dir) /
                             (std::filesystem::path(path).stem().string() + "_labels.png"))
                                .string();
    scenes.push_back(
        research::report_mosd_scene(model, path, png, options, context, truth_request(args, path)));
    if (!args.quiet)
      std::fprintf(stderr, "%s: %.2f%% of %llu table points plane, wrote %s\n", path.c_str(),
                   100.0 * scenes.back().plane_share(),
                   static_cast<unsigned long long>(scenes.back().table_points), png.c_str());
  }
  const research::MosdReport report = research::summarize_mosd(std::move(scenes));
  const std::string json = research::mosd_report_json(report);
  const std::string json_path =
      (std::filesystem::path(args.mosd_dir) / "mosd_report.json").string();
  atomic_write_file(json_path, json);
  std::fputs((args.json ? json : research::mosd_report_text(report)).c_str(), stdout);
  return cli::kExitOk;
}

// The simulated Kinect's parameters measured on the table planes of the mOSD scenes in a folder.
int calibrate_kinect(const Arguments& args) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(args.calibrate_dir, ec))
    if (entry.path().extension() == ".pcd") files.push_back(entry.path().string());
  if (ec) throw std::runtime_error(args.calibrate_dir + ": cannot be read (" + ec.message() + ")");
  if (files.empty()) throw std::runtime_error(args.calibrate_dir + ": no .pcd file");
  std::sort(files.begin(), files.end());
  std::function<void(const std::string&)> progress;
  if (!args.quiet)
    progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const research::KinectCalibration calibration =
      research::calibrate_mosd(files, research::KinectCalibrationOptions{}, progress);
  std::string json = research::kinect_calibration_json(calibration);
  std::string text = research::kinect_calibration_text(calibration);
  if (args.fit_simulation) {
    const research::KinectSimulationFit fit =
        research::fit_kinect_simulation(calibration, progress);
    text += research::kinect_simulation_fit_text(fit);
    json::Json root = json::Json::parse(json);
    root["simulation_fit"] = {
        {"depth_noise", json::rounded(fit.depth_noise, "%.6g")},
        {"noise_correlation_px", fit.noise_correlation_px},
        {"independent_noise_share", fit.independent_noise_share},
        {"autocorrelation_rms", json::rounded(fit.autocorrelation_rms, "%.6g")},
        {"simulated_depth_noise", json::rounded(fit.simulated.depth_noise, "%.6g")},
        {"simulated_autocorrelation", fit.simulated.autocorrelation}};
    json = json::dump(root) + "\n";
  }
  if (!args.calibration_json.empty()) atomic_write_file(args.calibration_json, json);
  std::fputs((args.json ? json : text).c_str(), stdout);
  return cli::kExitOk;
}

int fig4(const Arguments& args) {
  research::Fig4Options options;
  options.scenes = args.fig4_scenes;
  options.threads = args.threads;
  if (!args.quiet)
    options.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const research::Fig4 result = research::run_fig4(options);
  research::write_fig4(result, args.fig4_dir);
  if (!args.json) {
    std::printf("%s", research::hik_text(result).c_str());
    return cli::kExitOk;
  }
  const research::ClassSignatures& s = result.signatures;
  json::Json classes = json::Json::array(), points = json::Json::array();
  for (std::uint32_t id : s.class_ids) classes.push_back(class_name(id));
  for (const auto count : s.points) points.push_back(count);
  json::Json hik = json::Json::array();
  for (Eigen::Index r = 0; r < result.hik.rows(); ++r) {
    json::Json row = json::Json::array();
    for (Eigen::Index c = 0; c < result.hik.cols(); ++c) row.push_back(score(result.hik(r, c)));
    hik.push_back(std::move(row));
  }
  const json::Json line = {
      {"classes", std::move(classes)}, {"points", std::move(points)}, {"hik", std::move(hik)}};
  std::printf("%s\n", json::dump(line).c_str());
  return cli::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Label clouds with a trained model and score them, or re-measure Table I."};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-eval"));
  app.name("primlabel-eval");
  Arguments args;
  auto* files = app.add_option("files", args.files, "clouds to label (.pcd or .ply)");
  auto* model = app.add_option("--model", args.model, "model file (primlabel-train -o)");
  app.add_flag("--json", args.json, "one JSON object per file (or per Table I row) on stdout");
  auto* no_truth =
      app.add_flag("--no-truth", args.no_truth,
                   "the files' labels are no primitive classes (e.g. segment ids): print the "
                   "predicted label histogram");
  app.add_option("--classes", args.classes, "class map of the files' labels (id name per line)");
  auto* out = app.add_option("--out", args.out, "write the predicted labels (one input file)");
  auto* primitives_out = app.add_option(
      "--primitives", args.primitives_json,
      "group the predicted labels into connected segments, fit each with its class's primitive "
      "(plane, cylinder, sphere, torus, edge line) and write them as JSON (one input file)");
  auto* objects_out = app.add_option(
      "--objects", args.objects_json,
      "with --tabletop-only: write the table and its objects (plane, hull; per object points, "
      "centroid, bounds, height, primitive ids with --primitives) as JSON (one input file)");
  auto* mosd =
      app.add_option("--mosd-report", args.mosd_dir,
                     "mOSD scenes (label 1-9 table): share of table points labeled plane, and a "
                     "labeled PNG per scene, into DIR (with mosd_report.json)")
          ->needs(model)
          ->excludes(no_truth)
          ->excludes(out)
          ->excludes(primitives_out)
          ->excludes(objects_out);
  auto* object_truth =
      app.add_flag("--object-truth", args.object_truth,
                   "--mosd-report: also fit box / cylinder models to the object segments, label "
                   "their points by the ground-truth rule and score the model on them per class")
          ->needs(mosd);
  auto* write_truth_dir =
      app.add_option("--write-truth", args.truth_dir,
                     "write the fitted object truth of each mOSD scene as DIR/<scene>_truth.pcd "
                     "(taxonomy labels, 0 unscored; a `segment` field); without --model only "
                     "that, with truth_fits.json")
          ->excludes(no_truth)
          ->excludes(out);
  auto* check = app.add_option("--truth-check", args.truth_check,
                               "the fitted truth's own error: fit and label N held-out synthetic "
                               "Kinect scenes and compare with their true labels, per class")
                    ->check(CLI::PositiveNumber);
  app.add_option("--truth-radius", args.truth_radius,
                 "label radius of the fitted truth (m), as primlabel-synth --radius")
      ->check(CLI::PositiveNumber);
  check->excludes(model)->excludes(files)->excludes(object_truth)->excludes(write_truth_dir);
  app.add_option("--confusion-png", args.confusion_png,
                 "confusion matrix over all scored files as PNG (rows true, columns predicted)")
      ->excludes(no_truth)
      ->excludes(mosd);
  app.add_flag("--tabletop-only", args.tabletop_only, "label only the table and the objects on it");
  auto* t1 = app.add_flag("--table1", args.table1,
                          "re-measure the paper's Table I on synthetic LMS400 scenes");
  app.add_option("--table1-train", args.table1_train, "Table I: training scenes (default 8)")
      ->check(CLI::PositiveNumber)
      ->needs(t1);
  app.add_option("--table1-test", args.table1_test, "Table I: test scenes (default 4)")
      ->check(CLI::PositiveNumber)
      ->needs(t1);
  app.add_flag("--no-pfh", args.no_pfh, "Table I: FPFH rows only")->needs(t1);
  app.add_option("--node-basis", args.node_basis,
                 "Table I: CRF / node-only node features, tent (default) or linear (as the paper)")
      ->check(CLI::IsMember({"tent", "linear"}))
      ->needs(t1);
  app.add_option("--node-knots", args.node_knots, std::string("Table I: ") + cli::kNodeKnotsHelp)
      ->delimiter(',')
      ->needs(t1);
  app.add_flag("--no-svm", args.no_svm, "Table I: no SVM rows")->needs(t1);
  app.add_option("--pfh-max-neighbors", args.pfh_max_neighbors,
                 "Table I: PFH uses the M nearest within the feature radius (default 40)")
      ->check(CLI::PositiveNumber)
      ->needs(t1);
  auto* f4 = app.add_option("--fig4", args.fig4_dir,
                            "write the paper's Fig. 4 (class-mean FPFH signatures, HIK distance "
                            "matrix; CSV and PNG) from synthetic LMS400 training scenes to DIR");
  app.add_option("--fig4-scenes", args.fig4_scenes, "Fig. 4: training scenes (default 3)")
      ->check(CLI::PositiveNumber)
      ->needs(f4);
  auto* calibrate = app.add_option(
      "--calibrate-kinect", args.calibrate_dir,
      "measure depth noise, disparity quantisation, density and missing returns on the table "
      "planes of the mOSD scenes (*.pcd, label 1-9 table) in DIR; fit the simulated Kinect");
  app.add_flag("--fit-simulation", args.fit_simulation,
               "--calibrate-kinect: also fit the simulator's correlated depth error by simulating "
               "bare-table frames (about 20 s of CPU)")
      ->needs(calibrate);
  app.add_option("--calibration-json", args.calibration_json,
                 "--calibrate-kinect: also write the calibration as JSON to FILE")
      ->needs(calibrate);
  app.add_option("--threads", args.threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  app.add_flag("-q,--quiet", args.quiet, "no progress on stderr");
  t1->excludes(model)->excludes(files)->excludes(f4)->excludes(calibrate);
  calibrate->excludes(model)->excludes(files)->excludes(f4);
  f4->excludes(model)->excludes(files);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "primlabel-eval: usage error: %s (see --help)\n", e.what());
    return cli::kExitUsage;
  }
  try {
    args.node_knots = cli::node_knots(args.node_basis, args.node_knots);  // resolved once
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "primlabel-eval: usage error: %s\n", e.what());
    return cli::kExitUsage;
  }
  const bool study =
      args.table1 || !args.fig4_dir.empty() || args.truth_check > 0 || !args.calibrate_dir.empty();
  const bool truth_only = !args.truth_dir.empty() && args.model.empty();
  if (!args.truth_dir.empty() && !args.model.empty() && args.mosd_dir.empty()) {
    std::fprintf(stderr,
                 "primlabel-eval: usage error: --write-truth with --model needs --mosd-report\n");
    return cli::kExitUsage;
  }
  if (truth_only && args.files.empty()) {
    std::fprintf(stderr, "primlabel-eval: usage error: --write-truth needs mOSD scene files\n");
    return cli::kExitUsage;
  }
  if (!study && !truth_only && (args.model.empty() || args.files.empty())) {
    std::fprintf(stderr,
                 "primlabel-eval: usage error: give --model and at least one file, or --table1 "
                 "or --fig4 or --calibrate-kinect (see --help)\n");
    return cli::kExitUsage;
  }
  if (!args.out.empty() && args.files.size() != 1) {
    std::fprintf(stderr, "primlabel-eval: usage error: --out takes exactly one input file\n");
    return cli::kExitUsage;
  }
  if (!args.primitives_json.empty() && args.files.size() != 1) {
    std::fprintf(stderr,
                 "primlabel-eval: usage error: --primitives takes exactly one input file\n");
    return cli::kExitUsage;
  }
  if (!args.objects_json.empty() && (args.files.size() != 1 || !args.tabletop_only)) {
    std::fprintf(stderr,
                 "primlabel-eval: usage error: --objects takes exactly one input file "
                 "and needs --tabletop-only\n");
    return cli::kExitUsage;
  }
  try {
    if (args.table1) return table1(args);
    if (!args.fig4_dir.empty()) return fig4(args);
    if (!args.calibrate_dir.empty()) return calibrate_kinect(args);
    if (args.truth_check > 0) return truth_check(args);
    if (truth_only) return write_truth(args);
    if (!args.mosd_dir.empty()) return mosd_report(args);
    return evaluate_files(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-eval: error: %s\n", e.what());
    return cli::kExitFailure;
  }
}
