// primlabel-eval: labels clouds with a trained model and scores them against their ground truth
// (or, without one, prints the predicted label histogram). The paper's reproductions and the
// studies of real scenes are primlabel-research's subcommands.
//
//   primlabel-eval --model table.plm scene.pcd [--json] [--out labeled.pcd]
//   primlabel-eval --model table.plm scene.pcd --primitives scene_primitives.json  # instances
//   primlabel-eval --model table.plm --no-truth mosd_scene.pcd     # predicted label histogram
//   primlabel-eval --model table.plm --confusion-png confusion.png a.pcd b.pcd   # over all files

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

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
#include "primlabel/tabletop/objects_json.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string model, classes, out, primitives_json, objects_json, confusion_png;
  std::vector<std::string> files;
  bool json = false, no_truth = false, tabletop_only = false, quiet = false, plane_cascade = false;
  bool crease_points = pipeline::LabelingOptions{}.crease_points;
  int threads = 0;
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
    options.plane_cascade = args.plane_cascade;
    options.crease_points = args.crease_points;
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

// The research modes primlabel-eval had until issue 32 and their flags, now subcommands of
// primlabel-research: an old script is told where its command went, not only that a flag is
// unknown. The modes come first, so a mode's own flag names it over its companions.
std::optional<std::string> moved_to_research(int argc, char** argv) {
  struct Moved {
    std::string_view flag, subcommand;
  };
  static constexpr Moved kMoved[] = {
      {"--table1", "table1"},
      {"--fig4", "fig4"},
      {"--mosd-report", "mosd-report"},
      {"--write-truth", "write-truth"},
      {"--truth-check", "truth-check"},
      {"--calibrate-kinect", "calibrate-kinect"},
      {"--table1-train", "table1"},
      {"--table1-test", "table1"},
      {"--no-pfh", "table1"},
      {"--no-svm", "table1"},
      {"--pfh-max-neighbors", "table1"},
      {"--node-basis", "table1"},
      {"--node-knots", "table1"},
      {"--fig4-scenes", "fig4"},
      {"--object-truth", "mosd-report"},
      {"--fit-simulation", "calibrate-kinect"},
      {"--calibration-json", "calibrate-kinect"},
  };
  for (const Moved& moved : kMoved)
    for (int i = 1; i < argc; ++i) {
      const std::string_view arg = argv[i];
      if (arg == "--") break;  // file names from here on
      if (arg == moved.flag ||
          (arg.starts_with(moved.flag) && arg.substr(moved.flag.size()).starts_with('=')))
        return std::string(moved.flag) + " moved to primlabel-research: run `primlabel-research " +
               std::string(moved.subcommand) + "` (see its --help)";
    }
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Label clouds with a trained model and score them against their ground truth."};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-eval"));
  app.name("primlabel-eval");
  Arguments args;
  app.add_option("files", args.files, "clouds to label (.pcd or .ply)")->required();
  app.add_option("--model", args.model, "model file (primlabel-train -o)")->required();
  app.add_flag("--json", args.json, "one JSON object per file on stdout");
  auto* no_truth =
      app.add_flag("--no-truth", args.no_truth,
                   "the files' labels are no primitive classes (e.g. segment ids): print the "
                   "predicted label histogram");
  app.add_option("--classes", args.classes, "class map of the files' labels (id name per line)");
  app.add_option("--out", args.out, "write the predicted labels (one input file)");
  app.add_option(
      "--primitives", args.primitives_json,
      "group the predicted labels into connected segments, fit each with its class's primitive "
      "(plane, cylinder, sphere, torus, edge line) and write them as JSON (one input file)");
  app.add_option(
      "--objects", args.objects_json,
      "with --tabletop-only: write the table and its objects (plane, hull; per object points, "
      "centroid, bounds, height, primitive ids with --primitives) as JSON (one input file)");
  app.add_option("--confusion-png", args.confusion_png,
                 "confusion matrix over all scored files as PNG (rows true, columns predicted)")
      ->excludes(no_truth);
  app.add_flag("--tabletop-only", args.tabletop_only, "label only the table and the objects on it");
  app.add_flag("--plane-cascade", args.plane_cascade,
               "label points that are planar within the scene's plane noise plane without "
               "describing them (faster; see LabelingOptions::plane_cascade)");
  app.add_flag("--crease-points,!--no-crease-points", args.crease_points,
               "near creases label each input point at its own position, not by its voxel "
               "(see LabelingOptions::crease_points)")
      ->default_str(args.crease_points ? "on" : "off");
  app.add_option("--threads", args.threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  app.add_flag("-q,--quiet", args.quiet, "no progress on stderr");

  if (const auto moved = moved_to_research(argc, argv)) {
    std::fprintf(stderr, "primlabel-eval: usage error: %s\n", moved->c_str());
    return cli::kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "primlabel-eval: usage error: %s (see --help)\n", e.what());
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
    return evaluate_files(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-eval: error: %s\n", e.what());
    return cli::kExitFailure;
  }
}
