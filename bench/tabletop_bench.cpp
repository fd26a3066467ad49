// primlabel-bench tabletop: the table-top pre-filter per scene, optionally beside PCL's
// SACSegmentation + ConvexHull + ExtractPolygonalPrismData + EuclideanClusterExtraction (and,
// when PCL has it, LCCP on supervoxels) on the same input and thresholds. On labeled (mOSD)
// scans every method is scored: table F1, mean object IoU, objects found/true, whether the count
// is right (under-/over-segmented otherwise). Totals are printed for all scenes and, when the
// file names carry scene numbers (learn17.pcd), for odd and even numbers separately (develop on
// one half, hold out the other). Last line: JSON.
//
//   primlabel-bench tabletop ../shared/data/mosd/learn*.pcd --threads 2 --compare-pcl

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "bench_commands.hpp"
#include "pcl_availability.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/tabletop/segmentation_eval.hpp"
#include "primlabel/tabletop/tabletop.hpp"
#ifdef PRIMLABEL_HAVE_PCL
#include "tabletop_pcl_peer.hpp"
#endif

namespace {

using namespace primlabel;
using namespace primlabel::tabletop;

struct Arguments {
  std::vector<std::string> inputs;
  bool compare_pcl = false, no_crease_split = false, no_shape_split = false, no_colour = false;
  int threads = 2, repeat = 5;
};

// One method on one scene.
struct MethodRun {
  double ms = std::numeric_limits<double>::quiet_NaN();
  bool found = false;  // a table was found (unscored otherwise)
  SegmentationScores scores;
};

struct Row {
  std::string file;
  std::optional<int> number;  // the scene number in the file name, if any
  bool labeled = false;
  std::vector<MethodRun> runs;  // one per method, in the order of `methods`
};

// Figures of one method over a set of scenes.
struct Totals {
  std::size_t scenes = 0, scored = 0, count_right = 0, under = 0, over = 0;
  std::size_t found = 0, truth = 0;
  double f1_sum = 0, iou_sum = 0, ms_sum = 0;
  double worst_f1 = 1.0, worst_iou = 1.0;

  void add(const MethodRun& run, bool labeled) {
    ++scenes;
    ms_sum += run.ms;
    if (!labeled) return;
    ++scored;
    const SegmentationScores& s = run.scores;  // zeros when no table was found
    f1_sum += s.table_f1;
    iou_sum += s.mean_object_iou;
    worst_f1 = std::min(worst_f1, s.table_f1);
    worst_iou = std::min(worst_iou, s.mean_object_iou);
    found += s.objects_found;
    truth += s.objects_true;
    if (run.found && s.objects_found == s.objects_true) ++count_right;
    if (!run.found || s.objects_found < s.objects_true) ++under;
    if (run.found && s.objects_found > s.objects_true) ++over;
  }
};

// The JSON line's figures at 4 significant digits; null when not finite.
json::Json number(double v) { return json::rounded(v, "%.4g"); }

std::optional<int> scene_number(const std::string& file) {
  const std::string stem = std::filesystem::path(file).stem().string();
  std::size_t end = stem.size(), begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
  if (begin == end) return std::nullopt;
  return std::stoi(stem.substr(begin, std::min<std::size_t>(end - begin, 9)));
}

MethodRun run_ours(const PointCloud& cloud, const TabletopOptions& options,
                   const RunContext& context, int repeat, const std::string& path) {
  MethodRun run;
  TabletopResult result;
  run.ms = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repeat; ++r) {
    result = segment_tabletop(cloud, options, context);
    run.ms = std::min(run.ms, result.timings.total_ms);
  }
  if (!result.ok()) throw std::runtime_error(path + ": " + result.message);
  run.found = true;
  if (cloud.has_labels()) run.scores = evaluate_segmentation(cloud, result);
  return run;
}

#ifdef PRIMLABEL_HAVE_PCL
// Scores a peer's table and clusters with our evaluation.
MethodRun score_peer(const PointCloud& cloud, const bench::PclTabletopResult& peer, double ms) {
  MethodRun run;
  run.ms = ms;
  run.found = peer.found;
  if (cloud.has_labels() && peer.found) {
    TabletopResult as_ours;
    as_ours.status = TabletopStatus::kOk;
    as_ours.table_inliers = peer.table_inliers;
    as_ours.clusters = peer.clusters;
    run.scores = evaluate_segmentation(cloud, as_ours);
  }
  return run;
}

bench::PclTabletopOptions peer_options(const PointCloud& cloud, const TabletopOptions& options) {
  bench::PclTabletopOptions pcl_options;
  // The same search as ours: PCL's axis prior and angle are our up prior and cone.
  pcl_options.axis = (cloud.viewpoint.orientation.normalized() * Vec3f(0, -1, 0));
  pcl_options.max_angle_deg = options.estimate_prior_angle_deg;
  pcl_options.distance_threshold = options.plane.distance_threshold;
  pcl_options.max_iterations = options.plane.max_iterations;
  pcl_options.probability = options.plane.confidence;
  pcl_options.table_band = options.table_band;
  pcl_options.max_height = options.max_object_height;
  pcl_options.cluster_tolerance = options.clusters.tolerance;
  pcl_options.min_cluster_size = static_cast<int>(options.clusters.min_size);
  pcl_options.max_cluster_size = static_cast<int>(options.clusters.max_size);
  return pcl_options;
}

template <typename Peer>
MethodRun run_peer(const PointCloud& cloud, int repeat, Peer&& peer) {
  bench::PclTabletopResult result;
  double ms = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repeat; ++r) {
    result = peer();
    ms = std::min(ms, result.ms);
  }
  return score_peer(cloud, result, ms);
}
#endif

void print_run(const char* name, const MethodRun& run, bool labeled) {
  std::printf(" | %s %7.1f ms", name, run.ms);
  if (!labeled) return;
  if (!run.found) {
    std::printf(" (no table)");
    return;
  }
  const SegmentationScores& s = run.scores;
  const char* count = s.objects_found == s.objects_true  ? "ok"
                      : s.objects_found < s.objects_true ? "under"
                                                         : "over";
  std::printf(" F1 %.4f IoU %.3f %2zu/%-2zu %-5s", s.table_f1, s.mean_object_iou, s.objects_found,
              s.objects_true, count);
}

void print_totals(const char* group, const std::vector<std::string>& methods,
                  const std::vector<Totals>& totals) {
  for (std::size_t m = 0; m < methods.size(); ++m) {
    const Totals& t = totals[m];
    if (t.scenes == 0) continue;
    std::printf("%-5s %-5s %2zu scenes %7.1f ms", group, methods[m].c_str(), t.scenes,
                t.ms_sum / double(t.scenes));
    if (t.scored > 0) {
      const double n = double(t.scored);
      std::printf(
          " | table F1 %.4f (worst %.4f) | object IoU %.3f (worst %.3f) | objects %zu/%zu | "
          "count right %zu/%zu (%.0f%%) | under %zu over %zu",
          t.f1_sum / n, t.worst_f1, t.iou_sum / n, t.worst_iou, t.found, t.truth, t.count_right,
          t.scored, 100.0 * double(t.count_right) / n, t.under, t.over);
    }
    std::printf("\n");
  }
}

json::Json totals_json(const Totals& t) {
  json::Json j = {{"scenes", t.scenes}, {"mean_ms", number(t.ms_sum / double(t.scenes))}};
  if (t.scored > 0) {
    const double n = double(t.scored);
    j["mean_table_f1"] = number(t.f1_sum / n);
    j["worst_table_f1"] = number(t.worst_f1);
    j["mean_object_iou"] = number(t.iou_sum / n);
    j["worst_object_iou"] = number(t.worst_iou);
    j["objects_found"] = t.found;
    j["objects_true"] = t.truth;
    j["count_right"] = t.count_right;
    j["count_right_share"] = number(double(t.count_right) / n);
    j["under_segmented"] = t.under;
    j["over_segmented"] = t.over;
  }
  return j;
}

int run_tabletop_bench(const Arguments& args) {
#ifndef PRIMLABEL_HAVE_PCL
  if (args.compare_pcl) {
    std::fprintf(stderr, "primlabel-bench tabletop: error: --compare-pcl needs PCL: %s\n",
                 primlabel::bench::pcl_unavailable_reason(
                     "PCL 1.13 with its segmentation and surface components")
                     .c_str());
    return primlabel::kExitFailure;
  }
#endif
  TabletopOptions options;
  options.creases.enabled = !args.no_crease_split;
  options.shapes.enabled = !args.no_shape_split;
  options.shapes.use_colour = !args.no_colour;
  const RunContext context{args.threads};
  std::vector<std::string> methods = {"ours"};
  if (args.compare_pcl) {
    methods.push_back("pcl");
#ifdef PRIMLABEL_HAVE_PCL
    if (bench::pcl_has_lccp()) methods.push_back("lccp");
#endif
  }
  std::vector<Row> rows;
  for (const std::string& path : args.inputs) {
    const PointCloud cloud = read_cloud(path);
    Row row;
    row.file = std::filesystem::path(path).filename().string();
    row.number = scene_number(row.file);
    row.labeled = cloud.has_labels();
    row.runs.push_back(run_ours(cloud, options, context, args.repeat, path));
#ifdef PRIMLABEL_HAVE_PCL
    if (args.compare_pcl) {
      const bench::PclTabletopOptions pcl_options = peer_options(cloud, options);
      row.runs.push_back(
          run_peer(cloud, args.repeat, [&] { return bench::pcl_tabletop(cloud, pcl_options); }));
      if (methods.size() > 2)
        row.runs.push_back(
            run_peer(cloud, args.repeat, [&] { return bench::pcl_lccp(cloud, pcl_options); }));
    }
#endif
    std::printf("%-12s", row.file.c_str());
    for (std::size_t m = 0; m < methods.size(); ++m)
      print_run(methods[m].c_str(), row.runs[m], row.labeled);
    std::printf("\n");
    std::fflush(stdout);
    rows.push_back(std::move(row));
  }

  // Totals: all scenes, and odd / even scene numbers when every file has one.
  const bool numbered =
      std::all_of(rows.begin(), rows.end(), [](const Row& r) { return r.number.has_value(); });
  std::vector<std::pair<std::string, std::vector<Totals>>> groups;
  for (const char* group : {"odd", "even", "all"}) {
    const std::string name = group;
    if (name != "all" && !numbered) continue;
    std::vector<Totals> totals(methods.size());
    for (const Row& r : rows) {
      if (name == "odd" && *r.number % 2 == 0) continue;
      if (name == "even" && *r.number % 2 != 0) continue;
      for (std::size_t m = 0; m < methods.size(); ++m) totals[m].add(r.runs[m], r.labeled);
    }
    print_totals(group, methods, totals);
    groups.emplace_back(name, std::move(totals));
  }

  json::Json scenes = json::Json::array();
  for (const Row& r : rows) {
    json::Json scene = {{"file", r.file}};
    for (std::size_t m = 0; m < methods.size(); ++m) {
      const MethodRun& run = r.runs[m];
      const std::string& name = methods[m];
      scene[name + "_ms"] = number(run.ms);
      if (r.labeled && run.found) {
        scene[name + "_table_f1"] = number(run.scores.table_f1);
        scene[name + "_mean_object_iou"] = number(run.scores.mean_object_iou);
        scene[name + "_objects_found"] = run.scores.objects_found;
        scene[name + "_objects_true"] = run.scores.objects_true;
      }
    }
    scenes.push_back(std::move(scene));
  }
  json::Json summary = json::Json::object();
  for (const auto& [group, totals] : groups)
    for (std::size_t m = 0; m < methods.size(); ++m)
      summary[group][methods[m]] = totals_json(totals[m]);
  const Totals& all_ours = groups.back().second.front();
  json::Json line = {{"threads", args.threads},
                     {"repeat", args.repeat},
                     {"scenes", std::move(scenes)},
                     {"summary", std::move(summary)},
                     {"mean_ours_ms", number(all_ours.ms_sum / double(all_ours.scenes))}};
  if (args.compare_pcl) {
    const Totals& all_pcl = groups.back().second[1];
    line["mean_pcl_ms"] = number(all_pcl.ms_sum / double(all_pcl.scenes));
    line["speedup"] = number(all_pcl.ms_sum / all_ours.ms_sum);
  }
#ifdef PRIMLABEL_HAVE_PCL
  if (args.compare_pcl) line["pcl_version"] = bench::pcl_tabletop_version();
#endif
  std::printf("%s\n", json::dump(line).c_str());
  return primlabel::kExitOk;
}

}  // namespace

namespace primlabel::bench {

BenchCommand add_tabletop_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "tabletop", "Milliseconds per scene of the table-top pre-filter, optionally against PCL.");
  cmd->add_option("inputs", args->inputs, "scans (.pcd or .ply)")->required();
  cmd->add_flag("--compare-pcl", args->compare_pcl,
                "also time PCL's SACSegmentation + EuclideanClusterExtraction");
  cmd->add_flag("--no-crease-split", args->no_crease_split,
                "ours without the cut at concave creases (the previous pipeline)");
  cmd->add_flag("--no-shape-split", args->no_shape_split,
                "ours without the cut where fitted shapes or colours meet");
  cmd->add_flag("--no-colour", args->no_colour, "ours with the shape split but no colour evidence");
  cmd->add_option("--threads", args->threads, "threads for primlabel (PCL's steps are serial)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--repeat", args->repeat, "runs per scene; the fastest counts")
      ->check(CLI::PositiveNumber);
  return {cmd, [args] { return run_tabletop_bench(*args); }};
}

}  // namespace primlabel::bench
