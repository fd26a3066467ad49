// primlabel-synth: labeled synthetic table scenes, scanned by a simulated LMS400 or Kinect.
//
//   primlabel-synth --scene table --sensor lms400 --seed 7 -o scene.pcd
//   primlabel-synth --seed 7 -o scene.pcd --primitives scene_primitives.json   # the true shapes
//   primlabel-synth --set train --count 50 --out-dir data/ --sensor lms400
//   primlabel-synth --list-classes

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include "primlabel/build_version.hpp"
#include "primlabel/cli/cli_common.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/primitives/primitives_json.hpp"
#include "primlabel/synth/generate.hpp"
#include "primlabel/synth/true_primitives.hpp"

namespace {

using namespace primlabel;
using namespace primlabel::synth;

struct Arguments {
  std::string scene = "table", sensor = "lms400", output, set, out_dir, primitives;
  std::uint64_t seed = 1;
  int count = 0;
  double radius = kDefaultLabelRadius, noise_scale = 1.0, dropout = -1, angular_step = 0;
  double keep = 1.0, range_scale = 1.0, elevation = 0.0;
  int lines = 0, min_objects = 0, max_objects = 0;
  bool list_classes = false, quiet = false;
  bool segment_labels = false;  // --segment-labels: `label` holds instances, as in mOSD
};

// mOSD's convention (its README): 0 no point, 1-9 the table, 10 m + part for object m >= 2, so
// object k of the scene (k >= 1) is 10 (k + 1). The table is its top: the slab's sides (world z
// more than 15 mm below the top, beyond the depth noise) are 0, neither table nor object, as the
// table-top stage is to find the supporting surface.
void to_segment_labels(Generated& scan) {
  PointCloud& cloud = scan.cloud;
  const FloatField* object = cloud.find_field("object");
  if (!object) throw std::runtime_error("the scan has no object field");
  cloud.labels.assign(cloud.size(), 0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const float k = object->values[i];
    if (!is_finite(cloud.xyz[i]) || !(k >= 0)) continue;
    if (k == 0 && cloud.xyz[i].z() < -0.015f) continue;  // the scanners write world coordinates
    cloud.labels[i] = k == 0 ? 1u : 10u * (static_cast<std::uint32_t>(k) + 1u);
  }
  scan.tags["labels"] = "segments: 1 table top, 10 (k + 1) object k (mOSD)";
}

GenerateOptions options_from(const Arguments& args, std::uint64_t seed) {
  GenerateOptions options;
  options.scene = *scene_from_name(args.scene);
  options.sensor = *sensor_from_name(args.sensor);
  options.seed = seed;
  options.label_radius = args.radius;
  options.noise_scale = args.noise_scale;
  if (args.dropout >= 0) options.dropout = args.dropout;
  if (args.lines > 0) options.lms400_lines = args.lines;
  if (args.angular_step > 0) options.lms400_angular_step_deg = args.angular_step;
  options.keep = args.keep;
  options.placement.range_scale = args.range_scale;
  options.placement.elevation_deg = args.elevation;
  if (args.min_objects > 0) options.table.min_objects = args.min_objects;
  if (args.max_objects > 0) options.table.max_objects = args.max_objects;
  options.table.max_objects = std::max(options.table.max_objects, options.table.min_objects);
  return options;
}

// "plane 61.2%, edge-convex 8.0%, ..." over the points with finite coordinates.
std::string class_summary(const PointCloud& cloud, std::size_t& valid, std::size_t& on_objects) {
  std::map<std::uint32_t, std::size_t> counts;
  valid = on_objects = 0;
  const FloatField* object = cloud.find_field("object");
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!is_finite(cloud.xyz[i])) continue;
    ++valid;
    ++counts[cloud.labels[i]];
    if (object && object->values[i] > 0) ++on_objects;
  }
  std::string out;
  for (const auto& [label, n] : counts) {
    char entry[96];
    const auto cls = class_from_id(label);
    std::snprintf(entry, sizeof entry, "%s%s %.1f%%", out.empty() ? "" : ", ",
                  cls ? std::string(name(*cls)).c_str() : "?", 100.0 * double(n) / double(valid));
    out += entry;
  }
  return out;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The scene's true primitives as primlabel-eval --primitives writes fitted ones, plus each one's
// object; `points` counts the scan's points of its class within a few noise levels of it (0:
// not seen).
void write_true_primitives(const std::string& path, const Generated& scan, double noise_scale) {
  std::vector<TruePrimitive> truth = true_primitives(scan.scene);
  const double tolerance = 0.003 * std::max(1.0, noise_scale);
  count_points_on(truth, scan.cloud, tolerance);
  json::Json list = json::Json::array();
  for (std::size_t i = 0; i < truth.size(); ++i) {
    json::Json entry = primitives::to_json(truth[i].primitive, i);
    entry["object"] = truth[i].object;
    // own_points: the visibility rule `primlabel-bench primitives` applies.
    entry["own_points"] = truth[i].own_points;
    list.push_back(std::move(entry));
  }
  const json::Json out = {{"source", "primlabel-synth ground truth"},
                          {"points_tolerance", json::rounded(tolerance, "%.4g")},
                          {"primitives", std::move(list)}};
  atomic_write_file(path, json::dump(out, 1) + "\n");
}

int write_one(const Arguments& args) {
  const auto start = std::chrono::steady_clock::now();
  Generated scan = generate(options_from(args, args.seed));
  const double generate_seconds = seconds_since(start);
  std::size_t valid, on_objects;
  const std::string summary = class_summary(scan.cloud, valid, on_objects);
  if (args.segment_labels) to_segment_labels(scan);
  write_tagged_cloud(args.output, scan.cloud, scan.tags);
  if (!args.primitives.empty()) write_true_primitives(args.primitives, scan, args.noise_scale);
  if (!args.quiet) {
    std::fprintf(stderr,
                 "%s scene (seed %llu, %s, label radius %g m): %zu points (%zu on %zu objects: %s) "
                 "in %.2f s; labels: %s; wrote %s\n",
                 args.scene.c_str(), static_cast<unsigned long long>(args.seed),
                 args.sensor.c_str(), args.radius, valid, on_objects, scan.scene.objects.size() - 1,
                 scan.tags.at("objects").c_str(), generate_seconds, summary.c_str(),
                 args.output.c_str());
  }
  return cli::kExitOk;
}

int write_set(const Arguments& args) {
  const SceneSet set = *set_from_name(args.set);
  std::filesystem::create_directories(args.out_dir);
  const std::filesystem::path dir(args.out_dir);
  write_class_map((dir / "classes.txt").string(), ClassMap::taxonomy());
  json::Json scenes = json::Json::array();
  for (int i = 0; i < args.count; ++i) {
    const std::uint64_t seed = set_seed(set, i);
    char file[64];
    std::snprintf(file, sizeof file, "%s_%04d.pcd", args.set.c_str(), i);
    Generated scan = generate(options_from(args, seed));
    if (args.segment_labels) to_segment_labels(scan);
    write_tagged_cloud((dir / file).string(), scan.cloud, scan.tags);
    const std::string truth_file = std::filesystem::path(file).stem().string() + "_primitives.json";
    write_true_primitives((dir / truth_file).string(), scan, args.noise_scale);
    const std::size_t valid = count_finite(scan.cloud);
    scenes.push_back({{"file", file},
                      {"primitives", truth_file},
                      {"seed", seed},
                      {"points", valid},
                      {"objects", scan.tags.at("objects")}});
    if (!args.quiet)
      std::fprintf(stderr, "%s: %zu points (seed %llu)\n", file, valid,
                   static_cast<unsigned long long>(seed));
  }
  json::Json classes = json::Json::array();
  for (PrimitiveClass c : all_classes())
    classes.push_back({{"id", class_id(c)}, {"name", std::string(name(c))}});
  const json::Json manifest = {{"set", args.set},
                               {"scene", args.scene},
                               {"sensor", args.sensor},
                               {"label_radius", json::rounded(args.radius, "%.6g")},
                               {"classes", std::move(classes)},
                               {"scenes", std::move(scenes)}};
  const std::string manifest_path = (dir / (args.set + "_manifest.json")).string();
  atomic_write_file(manifest_path, json::dump(manifest, 2) + "\n");
  if (!args.quiet)
    std::fprintf(stderr, "wrote %d %s scenes and %s\n", args.count, args.set.c_str(),
                 manifest_path.c_str());
  return cli::kExitOk;
}

int usage_error(const std::string& message) {
  std::fprintf(stderr, "primlabel-synth: usage error: %s (see --help)\n", message.c_str());
  return cli::kExitUsage;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Labeled synthetic table scenes from a simulated laser line scanner or Kinect."};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-synth"));
  app.name("primlabel-synth");
  Arguments args;
  app.add_option("--scene", args.scene,
                 "table (random kitchen objects), primitives (one of each "
                 "shape), empty (bare table), clutter (8-14 objects close together, books, "
                 "stacked boxes: for the table-top stage) or crowded (clutter's hard cases: "
                 "objects in contact, stacks of one footprint, leaning boxes, a can beside a box "
                 "of its height and colour)")
      ->check(CLI::IsMember({"table", "primitives", "empty", "clutter", "crowded"}));
  app.add_flag("--segment-labels", args.segment_labels,
               "write instances, not classes, in `label`: 1 the table, 10 (k + 1) object k, as "
               "mOSD scenes do (primlabel-bench tabletop and primlabel-tabletop score them)");
  app.add_option("--sensor", args.sensor, "lms400 (tilting line laser) or kinect (640x480 depth)")
      ->check(CLI::IsMember({"lms400", "kinect"}));
  app.add_option("--seed", args.seed, "scene and noise seed (same seed, same cloud)");
  app.add_option("--radius", args.radius, "label radius r (m): the scale labels are defined at")
      ->check(CLI::PositiveNumber);
  app.add_option("-o,--output", args.output, "output cloud (.pcd or .ply)");
  app.add_option("--primitives", args.primitives,
                 "also write the scene's true primitives (planes, cylinders, spheres, tori, world "
                 "frame) as JSON; --set writes <scene>_primitives.json beside each scene");
  app.add_option("--set", args.set,
                 "write a scene set from its own seed range: train (1000..), "
                 "val (2000..), test (3000..)")
      ->check(CLI::IsMember({"train", "val", "test"}));
  app.add_option("--count", args.count, "scenes in the set (--set, which needs it)")
      ->check(CLI::Range(1, kMaxSetSize))
      ->default_str("");
  app.add_option("--out-dir", args.out_dir, "directory for the set's clouds and manifest (--set)");
  app.add_option("--noise-scale", args.noise_scale, "multiply the sensor noise (0 = exact)")
      ->check(CLI::NonNegativeNumber);
  // Unset (0, -1) means the sensor's or the scene's own value; --help says so.
  app.add_option("--dropout", args.dropout, "probability that a return is lost")
      ->check(CLI::Range(0.0, 0.99))
      ->default_str("the sensor's");
  app.add_option("--lines", args.lines, "lms400: sweep lines")
      ->check(CLI::PositiveNumber)
      ->default_str("the sensor's");
  app.add_option("--angular-step", args.angular_step, "lms400: degrees between beams of a line")
      ->check(CLI::Range(0.01, 5.0))
      ->default_str("the sensor's");
  app.add_option("--keep", args.keep, "random subsampling: the share of points kept (0, 1]")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--range-scale", args.range_scale,
                 "scale the sensor's distance from the table's front edge")
      ->check(CLI::PositiveNumber);
  app.add_option("--elevation", args.elevation,
                 "turn the sensor about the table's front edge by this many degrees (up: +)")
      ->check(CLI::Range(-59.0, 59.0));
  app.add_option("--min-objects", args.min_objects, "table scene: fewest objects")
      ->check(CLI::Range(1, 20))
      ->default_str("the scene's");
  app.add_option("--max-objects", args.max_objects, "table scene: most objects")
      ->check(CLI::Range(1, 20))
      ->default_str("the scene's");
  app.add_flag("--list-classes", args.list_classes,
               "print the classes as '<id> <name>' lines (a class map file) and exit");
  app.add_flag("-q,--quiet", args.quiet, "no summary on stderr");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    return usage_error(e.what());
  }
  if (args.list_classes) {
    std::fputs(ClassMap::taxonomy().to_text().c_str(), stdout);
    return cli::kExitOk;
  }
  const bool single = !args.output.empty(), many = !args.set.empty();
  if (single == many)
    return usage_error("give either -o OUT.pcd or --set NAME --count N --out-dir DIR");
  if (many && (args.count == 0 || args.out_dir.empty()))
    return usage_error("--set needs --count N and --out-dir DIR");
  if (single && (args.count > 0 || !args.out_dir.empty()))
    return usage_error("--count and --out-dir go with --set");
  try {
    return single ? write_one(args) : write_set(args);
  } catch (const std::invalid_argument& e) {
    return usage_error(e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-synth: error: %s\n", e.what());
    return cli::kExitFailure;
  }
}
