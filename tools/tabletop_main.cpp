// primlabel-tabletop: the table-top pre-filter on one scan: finds the table (largest horizontal
// plane), its boundary and the objects on it; scores the result against mOSD labels and renders
// it to PNG.
//
//   primlabel-tabletop learn0.pcd --eval --json --png learn0_tabletop.png

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "primlabel/build_version.hpp"
#include "primlabel/cli/cli_common.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/render/render.hpp"
#include "primlabel/tabletop/segmentation_eval.hpp"
#include "primlabel/tabletop/tabletop.hpp"

namespace {

using namespace primlabel;
using namespace primlabel::tabletop;

struct Arguments {
  std::string input, png, up, view = "oblique";
  bool eval = false, json = false, up_from_sensor = false, quiet = false;
  TabletopOptions options;
  int threads = 0;
};

constexpr std::uint32_t kTableColour = 0x4C72B0;
constexpr std::uint32_t kOtherColour = 0xC8C8C8;
constexpr std::uint32_t kClusterColours[] = {0xE6194B, 0x3CB44B, 0xFFB000, 0x911EB4, 0x46F0F0,
                                             0xF032E6, 0x9A6324, 0x808000, 0xFA8072, 0x000075};

std::uint32_t cluster_colour(std::size_t k) {
  return kClusterColours[k % (sizeof kClusterColours / sizeof kClusterColours[0])];
}

// The report's measurements at the 6 significant digits it has always printed.
json::Json measured(double value) { return json::rounded(value, "%.6g"); }

void render(const PointCloud& cloud, const TabletopResult& result, const Arguments& args,
            const std::string& title) {
  const std::vector<std::int32_t> ids = segment_ids(result, cloud.size());
  std::vector<std::uint32_t> colours(cloud.size(), kOtherColour);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (ids[i] == 0)
      colours[i] = kTableColour;
    else if (ids[i] > 0)
      colours[i] = cluster_colour(static_cast<std::size_t>(ids[i] - 1));
  RenderOptions options;
  options.view = args.view == "top"      ? RenderView::kTop
                 : args.view == "sensor" ? RenderView::kSensor
                                         : RenderView::kOblique;
  if (!result.ok())
    options.view = RenderView::kSensor;  // no up axis to look down
  else
    options.up = result.up;
  options.title = title;
  options.legend.push_back({"table", kTableColour});
  for (std::size_t k = 0; k < std::min<std::size_t>(result.clusters.size(), 8); ++k)
    options.legend.push_back({"object " + std::to_string(k + 1) + " (" +
                                  std::to_string(result.clusters[k].size()) + " points)",
                              cluster_colour(k)});
  options.legend.push_back({"other", kOtherColour});
  render_png(cloud, colours, options, args.png);
}

int run(const Arguments& args) {
  const PointCloud cloud = read_cloud(args.input);
  if (args.eval && !cloud.has_labels()) {
    std::fprintf(stderr, "primlabel-tabletop: error: %s has no 'label' field (--eval)\n",
                 args.input.c_str());
    return cli::kExitFailure;
  }
  const TabletopResult result = segment_tabletop(cloud, args.options, RunContext{args.threads});
  const std::string name = std::filesystem::path(args.input).filename().string();

  json::Json report = {{"file", args.input},
                       {"status", to_string(result.status)},
                       {"message", result.message},
                       {"points", cloud.size()},
                       {"valid_points", result.valid_points},
                       {"table_points", result.table_inliers.size()},
                       {"objects_found", result.clusters.size()}};
  if (result.ok()) {
    report["plane"] = {measured(result.plane[0]), measured(result.plane[1]),
                       measured(result.plane[2]), measured(result.plane[3])};
    report["tilt_deg"] = measured(result.tilt_deg);
    report["hull_vertices"] = result.hull.size();
    json::Json sizes = json::Json::array();
    for (const auto& cluster : result.clusters) sizes.push_back(cluster.size());
    report["cluster_sizes"] = std::move(sizes);
  }
  std::string title = name + ": " + to_string(result.status);
  // With --json stdout is the JSON line alone (for jq and scripts); the human lines go to stderr.
  FILE* human = args.json ? stderr : stdout;
  if (!args.quiet)
    std::fprintf(human, "%s: %s (%zu of %zu points valid), %.1f ms\n", name.c_str(),
                 result.message.c_str(), result.valid_points, cloud.size(),
                 result.timings.total_ms);
  if (args.eval && result.ok()) {
    const SegmentationScores scores = evaluate_segmentation(cloud, result);
    report["table_precision"] = measured(scores.table_precision);
    report["table_recall"] = measured(scores.table_recall);
    report["table_f1"] = measured(scores.table_f1);
    report["mean_object_iou"] = measured(scores.mean_object_iou);
    report["objects_true"] = scores.objects_true;
    json::Json ious = json::Json::array();
    for (const auto& object : scores.objects) ious.push_back(measured(object.best_iou));
    report["object_iou"] = std::move(ious);
    char text[200];
    std::snprintf(text, sizeof text,
                  "table precision %.4f recall %.4f F1 %.4f; mean object IoU %.4f (%zu found, "
                  "%zu true)",
                  scores.table_precision, scores.table_recall, scores.table_f1,
                  scores.mean_object_iou, scores.objects_found, scores.objects_true);
    if (!args.quiet) std::fprintf(human, "%s: %s\n", name.c_str(), text);
    char short_text[120];
    std::snprintf(short_text, sizeof short_text, " | table F1 %.3f, object IoU %.3f",
                  scores.table_f1, scores.mean_object_iou);
    title += short_text;
  }
  const TabletopTimings& t = result.timings;
  report["ms"] = measured(t.total_ms);
  report["ms_prepare"] = measured(t.prepare_ms);
  report["ms_plane"] = measured(t.plane_ms);
  report["ms_table"] = measured(t.table_ms);
  report["ms_objects"] = measured(t.objects_ms);
  report["ms_refine"] = measured(t.refine_ms);

  if (!args.png.empty()) {
    render(cloud, result, args, title);
    if (!args.quiet) std::fprintf(human, "%s: wrote %s\n", name.c_str(), args.png.c_str());
  }
  if (args.json) std::printf("%s\n", json::dump(report).c_str());
  if (!result.ok()) {
    std::fprintf(stderr, "primlabel-tabletop: error: %s: %s\n", args.input.c_str(),
                 result.message.c_str());
    return cli::kExitFailure;
  }
  return cli::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Find the table (the horizontal surface holding up the scene) and the objects on it in a "
      "scan; "
      "score against mOSD labels; render to PNG."};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-tabletop"));
  app.name("primlabel-tabletop");
  Arguments args;
  TabletopOptions& o = args.options;
  std::size_t min_size = o.clusters.min_size, max_size = o.clusters.max_size;
  app.add_option("input", args.input, "input cloud (.pcd or .ply)")->required();
  app.add_flag("--eval", args.eval,
               "score against the cloud's mOSD labels (1-9 table, 10k+ object k)");
  app.add_flag("--json", args.json,
               "print one JSON line of the results on stdout (the human lines go to stderr)");
  app.add_option("--png", args.png, "render the segmentation to this PNG");
  app.add_option("--view", args.view, "PNG view: oblique, top or sensor")
      ->check(CLI::IsMember({"oblique", "top", "sensor"}));
  auto* up = app.add_option("--up", args.up, "X,Y,Z up axis in the cloud's frame");
  app.add_flag("--up-from-sensor", args.up_from_sensor,
               "up = the sensor's -y turned by the VIEWPOINT pose (default: estimated)")
      ->excludes(up);
  app.add_option("--max-tilt", o.max_tilt_deg,
                 "table normal within this many degrees of a given/sensor up")
      ->check(CLI::Range(0.1, 90.0));
  app.add_option("--prior-angle", o.estimate_prior_angle_deg,
                 "estimated up: table within this many degrees of the sensor's up")
      ->check(CLI::Range(0.1, 90.0));
  app.add_option("--distance-threshold", o.plane.distance_threshold, "plane fit band (m)")
      ->check(CLI::PositiveNumber);
  app.add_option("--table-band", o.table_band, "table points: |height| at most this (m)")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-height", o.max_object_height, "objects: at most this high (m)")
      ->check(CLI::PositiveNumber);
  app.add_option("--cluster-tolerance", o.clusters.tolerance, "object clustering distance (m)")
      ->check(CLI::PositiveNumber);
  app.add_option("--min-cluster-size", min_size, "smallest object (points)");
  app.add_option("--max-cluster-size", max_size, "largest object (points)");
  bool no_split = false, no_merge = false, no_creases = false, no_shapes = false, no_colour = false;
  app.add_flag("--no-crease-split", no_creases,
               "keep touching objects in one cluster (no cut at concave creases)");
  app.add_flag("--no-shape-split", no_shapes,
               "keep touching objects in one cluster where their fitted shapes or colours meet");
  app.add_flag("--no-colour", no_colour,
               "shape split without colour evidence (colour not registered to depth)");
  app.add_flag("--no-split", no_split, "keep objects standing on objects in one cluster");
  app.add_flag("--no-merge", no_merge, "do not join parts of objects cut apart by occlusion");
  app.add_option("--voxel-leaf", o.voxel_leaf, "fit and cluster on voxel centroids (m; 0 = off)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--seed", o.seed, "RANSAC seed");
  app.add_option("--threads", args.threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  app.add_flag("-q,--quiet", args.quiet, "no summary lines (the JSON line stays)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "primlabel-tabletop: usage error: %s (see --help)\n", e.what());
    return cli::kExitUsage;
  }
  try {
    o.creases.enabled = !no_creases;
    o.shapes.enabled = !no_shapes;
    o.shapes.use_colour = !no_colour;
    o.split.enabled = !no_split;
    o.merge.enabled = !no_merge;
    o.clusters.min_size = min_size;
    o.clusters.max_size = max_size;
    if (!args.up.empty()) {
      o.up_source = UpAxisSource::kGiven;
      o.up = cli::parse_vec3(args.up);
    } else if (args.up_from_sensor) {
      o.up_source = UpAxisSource::kSensor;
    }
    o.validate();
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "primlabel-tabletop: usage error: %s\n", e.what());
    return cli::kExitUsage;
  }
  try {
    return run(args);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "primlabel-tabletop: usage error: %s\n", e.what());
    return cli::kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-tabletop: error: %s\n", e.what());
    return cli::kExitFailure;
  }
}
