// primlabel-train: trains a labeling model (CRF, node-only, SVM) from labeled synthetic scenes or
// labeled PCD/PLY files and writes a model file.
//
//   primlabel-train --synth-train 4 --synth-val 1 --sensor lms400 -o table.plm --curve curve.csv
//   primlabel-train --train a.pcd b.pcd --val c.pcd --classes map.txt --kind node -o m.plm
//   primlabel-train --train real*.pcd --synth-train 8 --sensor kinect -o mixed.plm  # both
//   primlabel-train --synth-train 3 --kind svm --svm-max-points 20000 -o svm.plm

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "node_basis.hpp"
#include "primlabel/build_version.hpp"
#include "primlabel/cli/cli_common.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/cloud_signature.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/pipeline/labeled_voxels.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/research/curve_plot.hpp"
#include "primlabel/synth/augment.hpp"
#include "primlabel/synth/generate.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  int synth_train = 8, synth_val = 1, iterations = 200, graph_k = 8, threads = 0;
  std::string sensor = "lms400", kind = "crf", objective = "piecewise", descriptor = "fpfh";
  std::string fpfh_variant = "paper", node_basis = "tent";
  double label_radius = synth::kDefaultLabelRadius, l2 = 1e-6, svm_c = 10.0, svm_gamma = 0.0;
  double class_balance = 0.0;
  std::size_t svm_max_points = 20000;
  std::vector<float> node_knots;  // --node-knots, then the resolved basis (cli::node_knots)
  float feature_radius = 0.025f, normal_radius = 0.01f;
  float voxel_size = 0.0f;         // > 0: train on voxels of this edge and record it in the model
  float feature_sample = 0.0f;     // > 0: FPFH against one point per voxel of this edge
  std::vector<float> extra_radii;  // --extra-radii: the descriptor at further scales
  bool surface_variation_features = false;  // --surface-variation
  bool shape_evidence = false;              // --shape-evidence
  std::vector<std::string> train_files, val_files;
  std::string sensor_name;  // --sensor-name: the sensor of --train files
  // --train with an explicit --synth-train: the synthetic scenes are trained on beside the files.
  bool synth_with_files = false;
  std::string classes, output, curve_csv, curve_png, name, augment, attribution;
  synth::Augmentation augmentation;  // --augment, parsed
  bool quiet = false;
};

void say(const Arguments& args, const std::string& line) {
  if (!args.quiet) std::fprintf(stderr, "%s\n", line.c_str());
}

std::vector<pipeline::SceneData> load_scenes(const Arguments& args, bool validation,
                                             const FeatureSettings& features,
                                             const crf::GraphSettings& graph) {
  const std::vector<std::uint32_t> every_class = [] {
    std::vector<std::uint32_t> ids;
    for (PrimitiveClass c : all_classes()) ids.push_back(class_id(c));
    return ids;
  }();
  std::vector<pipeline::SceneData> scenes;
  auto add = [&](PointCloud cloud, const std::string& source) {
    const auto start = std::chrono::steady_clock::now();
    // The density the model is served at: label_cloud downsamples to the model's voxel size.
    const std::uint32_t width = cloud.organized() ? cloud.width : 0;
    const std::uint32_t height = cloud.organized() ? cloud.height : 0;
    const CloudSignature acquired =
        measure_signature(cloud.xyz, cloud.viewpoint.origin, RunContext{args.threads});
    if (args.voxel_size > 0.0f)
      cloud = pipeline::voxelize_labeled(cloud, args.voxel_size, RunContext{args.threads});
    scenes.push_back(pipeline::prepare_scene(std::move(cloud), source, features, graph, every_class,
                                             RunContext{args.threads}));
    scenes.back().image_width = width;  // the frame as acquired, not its voxels
    scenes.back().image_height = height;
    scenes.back().acquired = acquired;
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char line[512];
    std::snprintf(line, sizeof line, "%s: %s, %zu points described in %.1f s",
                  validation ? "validation" : "training", source.c_str(),
                  scenes.back().truth.size(), s);
    say(args, line);
  };
  const auto& files = validation ? args.val_files : args.train_files;
  if (!args.train_files.empty()) {
    const ClassMap map = args.classes.empty() ? ClassMap{} : read_class_map(args.classes);
    for (const std::string& path : files)
      add(args.classes.empty() ? load_labeled_cloud(path) : load_labeled_cloud(path, map), path);
    if (!args.synth_with_files) return scenes;
  }
  const auto sensor = synth::sensor_from_name(args.sensor);
  const auto set = validation ? synth::SceneSet::kVal : synth::SceneSet::kTrain;
  const int count = validation ? args.synth_val : args.synth_train;
  for (int i = 0; i < count; ++i) {
    const std::string source = "synth:" + args.sensor + ":" + std::string(synth::set_name(set)) +
                               ":seed" + std::to_string(synth::set_seed(set, i));
    synth::GenerateOptions options;
    options.sensor = *sensor;
    options.seed = synth::set_seed(set, i);
    options.label_radius = args.label_radius;
    add(synth::generate(options).cloud, source);
    // Training scenes also in augmented variants; validation stays as the sensor scans nominally.
    for (int copy = 0; !validation && copy < args.augmentation.copies; ++copy) {
      const synth::GenerateOptions variant = synth::augmented(options, args.augmentation, copy);
      char how[160];
      std::snprintf(how, sizeof how, ":aug%d(noise %.2f, keep %.2f, range %.2f, elevation %+.1f)",
                    copy, variant.noise_scale, variant.keep, variant.placement.range_scale,
                    variant.placement.elevation_deg);
      add(synth::generate(variant).cloud, source + how);
    }
  }
  return scenes;
}

int run(const Arguments& args) {
  FeatureSettings features;
  features.descriptor = args.descriptor == "pfh" ? DescriptorKind::kPfh : DescriptorKind::kFpfh;
  features.fpfh_variant =
      args.fpfh_variant == "paper" ? FpfhVariant::kWithOwnSpfh : FpfhVariant::kPcl;
  features.normals = Neighborhood::Radius(args.normal_radius);
  features.features = Neighborhood::Radius(args.feature_radius);
  features.feature_sample_size = args.feature_sample;
  features.extra_feature_radii = args.extra_radii;
  features.surface_variation_features = args.surface_variation_features;
  features.shape_evidence = args.shape_evidence;
  crf::GraphSettings graph;
  graph.neighborhood = Neighborhood::Knn(args.graph_k);

  std::vector<pipeline::SceneData> train = load_scenes(args, false, features, graph);
  std::vector<pipeline::SceneData> val = load_scenes(args, true, features, graph);
  const std::vector<std::uint32_t> class_ids = pipeline::classes_present(train);
  if (class_ids.empty()) {
    std::fprintf(stderr, "primlabel-train: error: the training data has no labeled point\n");
    return cli::kExitFailure;
  }
  for (auto* set : {&train, &val})
    for (auto& scene : *set) pipeline::assign_labels(scene, class_ids);
  std::string names;
  for (std::uint32_t id : class_ids) names += " " + std::string(name(*class_from_id(id)));
  say(args, "classes:" + names);

  pipeline::ModelTrainingOptions options;
  options.kind = args.kind == "node"  ? ModelKind::kNodeOnly
                 : args.kind == "svm" ? ModelKind::kSvm
                                      : ModelKind::kCrf;
  options.svm.c = args.svm_c;
  options.svm.gamma = args.svm_gamma;
  options.svm.max_training_points = args.svm_max_points;
  options.objective = args.objective == "bethe" ? crf::TrainingObjective::kBetheBp
                      : args.objective == "pl"  ? crf::TrainingObjective::kPseudoLikelihood
                                                : crf::TrainingObjective::kPiecewise;
  options.l2 = args.l2;
  options.iterations = args.iterations;
  options.node_knots = args.node_knots;
  options.class_balance = args.class_balance;
  std::vector<crf::TrainingIteration> curve;
  if (options.kind != ModelKind::kSvm && (!args.curve_csv.empty() || !args.curve_png.empty()))
    options.on_iteration = [&](const crf::TrainingIteration& it) {
      curve.push_back(it);
      char line[256];
      std::snprintf(
          line, sizeof line, "iteration %d: objective %.5f, train %.4f, validation %.4f (%.1f s)",
          it.iteration, it.objective, it.train_accuracy, it.validation_accuracy, it.seconds);
      say(args, line);
    };
  say(args, "training " + args.kind + " (" +
                (options.kind == ModelKind::kNodeOnly ? std::string("node-only")
                 : options.kind == ModelKind::kSvm    ? std::string("libsvm RBF")
                                                      : args.objective) +
                ")...");
  pipeline::ModelTrainingResult trained = pipeline::train_label_model(
      train, val, class_ids, features, graph, options, RunContext{args.threads});
  LabelModel& model = trained.model;
  if (options.kind != ModelKind::kNodeOnly) say(args, model.training.objective);
  if (!args.name.empty()) model.name = args.name;
  model.features.voxel_size = args.voxel_size;  // applied by label_cloud (and so the server)
  // Part of the model's domain: the synthetic scenes' sensor, or the one named for the files.
  if (!args.sensor_name.empty())
    model.training.sensor = args.sensor_name;
  else if (args.train_files.empty() || args.synth_with_files)
    model.training.sensor = args.sensor;
  model.training.data_attribution = args.attribution;
  save_model(args.output, model);

  if (!args.curve_csv.empty()) {
    std::ostringstream csv;
    crf::write_training_curve_csv(csv, curve);
    atomic_write_file(args.curve_csv, csv.str());
  }
  if (!args.curve_png.empty()) research::write_curve_png(args.curve_png, curve);

  const std::string how = options.kind == ModelKind::kSvm
                              ? std::string("libsvm")
                              : std::to_string(trained.details.iterations) + " iterations (" +
                                    trained.details.message + ")";
  char line[512];
  std::snprintf(line, sizeof line, "trained in %.1f s, %s; validation accuracy %s; wrote %s",
                trained.seconds, how.c_str(),
                val.empty() ? "-" : std::to_string(model.validation.accuracy).c_str(),
                args.output.c_str());
  say(args, line);
  return cli::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Train a point labeling model (CRF, node-only or SVM) from labeled clouds."};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-train"));
  app.name("primlabel-train");
  Arguments args;
  auto* synth_train =
      app.add_option("--synth-train", args.synth_train, "synthetic training scenes (default 8)")
          ->check(CLI::PositiveNumber);
  auto* synth_val =
      app.add_option("--synth-val", args.synth_val, "synthetic validation scenes (default 1)")
          ->check(CLI::NonNegativeNumber);
  app.add_option("--sensor", args.sensor, "synthetic sensor: lms400 or kinect")
      ->check(CLI::IsMember({"lms400", "kinect"}));
  app.add_option("--radius", args.label_radius, "label radius of the synthetic ground truth (m)")
      ->check(CLI::PositiveNumber);
  auto* train_files = app.add_option(
      "--train", args.train_files,
      "labeled PCD/PLY training files (with --synth-train N: beside N synthetic scenes)");
  app.add_option("--sensor-name", args.sensor_name,
                 "the sensor that made the --train files (e.g. kinect), recorded in the model")
      ->needs(train_files);
  app.add_option("--val", args.val_files,
                 "labeled PCD/PLY validation files (with --synth-train: beside the --synth-val "
                 "scenes)")
      ->needs(train_files);
  app.add_option("--classes", args.classes, "class map of the files' labels (id name per line)")
      ->needs(train_files);
  app.add_option("--kind", args.kind, "crf, node (node-only) or svm")
      ->check(CLI::IsMember({"crf", "node", "svm"}));
  app.add_option("--svm-c", args.svm_c, "SVM: C (default 10)")->check(CLI::PositiveNumber);
  app.add_option("--svm-gamma", args.svm_gamma,
                 "SVM: RBF gamma (default 0: 1 / mean squared feature distance)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--svm-max-points", args.svm_max_points,
                 "SVM: train on at most this many points, a seeded subsample (default 20000)")
      ->check(CLI::PositiveNumber);
  app.add_option("--objective", args.objective,
                 "CRF objective: piecewise (default: node factors, then a validated coupling), "
                 "pl (pseudo-likelihood) or bethe (loopy BP)")
      ->check(CLI::IsMember({"piecewise", "pl", "bethe"}));
  app.add_option("--descriptor", args.descriptor, "fpfh or pfh")
      ->check(CLI::IsMember({"fpfh", "pfh"}));
  app.add_option("--fpfh-variant", args.fpfh_variant,
                 "paper (default: also the point's own SPFH, as Open3D) or pcl (as PCL)")
      ->check(CLI::IsMember({"pcl", "paper"}));
  app.add_option("--node-basis", args.node_basis,
                 "CRF / node-only node features: tent (default: a piecewise-linear function of "
                 "each bin) or linear (the bins themselves, as the paper)")
      ->check(CLI::IsMember({"tent", "linear"}));
  app.add_option("--node-knots", args.node_knots, cli::kNodeKnotsHelp)->delimiter(',');
  app.add_option("--l2", args.l2, "L2 regularisation (default 1e-6)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--class-balance", args.class_balance,
                 "CRF / node-only: weight each class's points by (N / (K n_c))^ALPHA, ALPHA in "
                 "[0, 1] (default 0: unweighted; 1: every class counts as much in total)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--iterations", args.iterations, "L-BFGS iterations (default 200)")
      ->check(CLI::PositiveNumber);
  app.add_option("--feature-radius", args.feature_radius, "descriptor radius (m, default 0.025)")
      ->check(CLI::PositiveNumber);
  app.add_option("--voxel-size", args.voxel_size,
                 "train on voxel centroids of this edge (m) and record it: the model is served "
                 "at that density (default 0: every point)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--feature-sample", args.feature_sample,
                 "FPFH neighbourhoods hold one point per voxel of this edge (m; every point is "
                 "still described and labeled) and the model records it (default 0: every "
                 "neighbour)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--normal-radius", args.normal_radius, "normal radius (m, default 0.01)")
      ->check(CLI::PositiveNumber);
  app.add_option("--extra-radii", args.extra_radii,
                 "multi-scale model input: the descriptor also at these radii (m, comma-separated, "
                 "at most 4; FPFH only); clients still get the one at --feature-radius")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  app.add_flag("--surface-variation", args.surface_variation_features,
               "multi-scale model input: also each point's surface variation at the normal, "
               "feature and extra radii (FPFH only)");
  app.add_flag("--shape-evidence", args.shape_evidence,
               "model input: also the class the box or cylinder fitted to each table-top object "
               "gives its points (the taxonomy's rule on the fitted shape; zeros where none fits)");
  app.add_option("--graph-k", args.graph_k, "CRF graph: K nearest neighbours (default 8)")
      ->check(CLI::PositiveNumber);
  app.add_option("--augment", args.augment,
                 "synthetic training: also scan each scene with other noise, density, range and "
                 "incidence, e.g. noise=0.5:4,density=0.25:1,range=0.9:1.4,elevation=-10:10,"
                 "copies=1 (noise log-uniform, the rest uniform; seeded by the scene)");
  app.add_option("--attribution", args.attribution,
                 "credit and licence of the training data, recorded in the model");
  app.add_option("-o,--output", args.output, "model file to write")->required();
  app.add_option("--name", args.name, "model name recorded in the file");
  app.add_option("--curve", args.curve_csv, "training curve CSV (objective, accuracies)");
  app.add_option("--curve-png", args.curve_png, "training curve plot (PNG)");
  app.add_option("--threads", args.threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  app.add_flag("-q,--quiet", args.quiet, "no progress on stderr");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "primlabel-train: usage error: %s (see --help)\n", e.what());
    return cli::kExitUsage;
  }
  // Synthetic scenes with files only when asked for; they alone can be augmented.
  args.synth_with_files = !args.train_files.empty() && synth_train->count() > 0;
  const bool synthetic = args.train_files.empty() || args.synth_with_files;
  const char* usage = nullptr;
  if (!args.augment.empty() && !synthetic)
    usage = "--augment rescans synthetic scenes: with --train it needs --synth-train";
  else if (synth_val->count() > 0 && !synthetic)
    usage = "--synth-val with --train needs --synth-train";
  else if (args.synth_with_files && !args.sensor_name.empty() && args.sensor_name != args.sensor)
    usage = "--sensor-name differs from the synthetic scenes' --sensor";
  else if (args.extra_radii.size() > kMaxExtraFeatureRadii)
    usage = "--extra-radii takes at most 4 radii";
  else if ((!args.extra_radii.empty() || args.surface_variation_features) &&
           args.descriptor != "fpfh")
    usage = "--extra-radii and --surface-variation need --descriptor fpfh";
  if (usage) {
    std::fprintf(stderr, "primlabel-train: usage error: %s\n", usage);
    return cli::kExitUsage;
  }
  try {  // before any scene is described
    args.node_knots = cli::node_knots(args.node_basis, args.node_knots);
    if (!args.augment.empty()) args.augmentation = synth::parse_augmentation(args.augment);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "primlabel-train: usage error: %s\n", e.what());
    return cli::kExitUsage;
  }
  if (args.kind == "svm" && (!args.curve_csv.empty() || !args.curve_png.empty())) {
    std::fprintf(stderr,
                 "primlabel-train: usage error: --curve and --curve-png need an iterative model "
                 "(--kind crf or node)\n");
    return cli::kExitUsage;
  }
  if (args.class_balance > 0.0 && (args.kind == "svm" || args.objective == "bethe")) {
    std::fprintf(stderr,
                 "primlabel-train: usage error: --class-balance needs --kind crf or node and a "
                 "per-point objective (piecewise or pl)\n");
    return cli::kExitUsage;
  }
  try {
    return run(args);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "primlabel-train: usage error: %s\n", e.what());
    return cli::kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-train: error: %s\n", e.what());
    return cli::kExitFailure;
  }
}
