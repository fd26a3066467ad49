// primlabel-bench-tabletop: milliseconds per scene of the table-top pre-filter, optionally beside
// PCL's SACSegmentation + ConvexHull + ExtractPolygonalPrismData + EuclideanClusterExtraction on
// the same input and thresholds. On labeled (mOSD) scans both are also scored. Last line: JSON.
//
//   primlabel-bench-tabletop ../shared/data/mosd/learn*.pcd --threads 2 --compare-pcl

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

#include "pcl_availability.hpp"
#include "primlabel/build_version.hpp"
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
  bool compare_pcl = false;
  int threads = 2, repeat = 5;
};

struct Row {
  std::string file;
  double ours_ms = 0, pcl_ms = std::numeric_limits<double>::quiet_NaN();
  SegmentationScores ours, pcl;
  bool labeled = false, pcl_found = false;
};

// The JSON line's figures at 4 significant digits; null when not finite.
json::Json number(double v) { return json::rounded(v, "%.4g"); }

int run(const Arguments& args) {
  std::vector<Row> rows;
  const TabletopOptions options;
  const RunContext context{args.threads};
  for (const std::string& path : args.inputs) {
    const PointCloud cloud = read_cloud(path);
    Row row;
    row.file = std::filesystem::path(path).filename().string();
    row.labeled = cloud.has_labels();
    TabletopResult result;
    row.ours_ms = std::numeric_limits<double>::infinity();
    for (int r = 0; r < args.repeat; ++r) {
      result = segment_tabletop(cloud, options, context);
      row.ours_ms = std::min(row.ours_ms, result.timings.total_ms);
    }
    if (!result.ok()) {
      std::fprintf(stderr, "primlabel-bench-tabletop: error: %s: %s\n", path.c_str(),
                   result.message.c_str());
      return primlabel::kExitFailure;
    }
    if (row.labeled) row.ours = evaluate_segmentation(cloud, result);
#ifdef PRIMLABEL_HAVE_PCL
    if (args.compare_pcl) {
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
      bench::PclTabletopResult pcl;
      row.pcl_ms = std::numeric_limits<double>::infinity();
      for (int r = 0; r < args.repeat; ++r) {
        pcl = bench::pcl_tabletop(cloud, pcl_options);
        row.pcl_ms = std::min(row.pcl_ms, pcl.ms);
      }
      row.pcl_found = pcl.found;
      if (row.labeled && pcl.found) {
        TabletopResult as_ours;
        as_ours.status = TabletopStatus::kOk;
        as_ours.table_inliers = pcl.table_inliers;
        as_ours.clusters = pcl.clusters;
        row.pcl = evaluate_segmentation(cloud, as_ours);
      }
    }
#endif
    std::printf("%-12s ours %7.1f ms", row.file.c_str(), row.ours_ms);
    if (row.labeled)
      std::printf(" (table F1 %.4f, object IoU %.3f, %zu/%zu objects)", row.ours.table_f1,
                  row.ours.mean_object_iou, row.ours.objects_found, row.ours.objects_true);
    if (args.compare_pcl) {
      std::printf(" | PCL %7.1f ms", row.pcl_ms);
      if (row.labeled && row.pcl_found)
        std::printf(" (table F1 %.4f, object IoU %.3f, %zu/%zu objects)", row.pcl.table_f1,
                    row.pcl.mean_object_iou, row.pcl.objects_found, row.pcl.objects_true);
      std::printf(" | PCL/ours %.1fx", row.pcl_ms / row.ours_ms);
    }
    std::printf("\n");
    rows.push_back(row);
  }

  double ours_total = 0, pcl_total = 0;
  json::Json scenes = json::Json::array();
  for (const Row& r : rows) {
    ours_total += r.ours_ms;
    pcl_total += r.pcl_ms;
    json::Json scene = {{"file", r.file}, {"ours_ms", number(r.ours_ms)}};
    if (r.labeled) {
      scene["ours_table_f1"] = number(r.ours.table_f1);
      scene["ours_mean_object_iou"] = number(r.ours.mean_object_iou);
    }
    if (args.compare_pcl) {
      scene["pcl_ms"] = number(r.pcl_ms);
      if (r.labeled && r.pcl_found) {
        scene["pcl_table_f1"] = number(r.pcl.table_f1);
        scene["pcl_mean_object_iou"] = number(r.pcl.mean_object_iou);
      }
    }
    scenes.push_back(std::move(scene));
  }
  const double n = double(std::max<std::size_t>(rows.size(), 1));
  json::Json line = {{"threads", args.threads},
                     {"repeat", args.repeat},
                     {"scenes", std::move(scenes)},
                     {"mean_ours_ms", number(ours_total / n)}};
  if (args.compare_pcl) {
    line["mean_pcl_ms"] = number(pcl_total / n);
    line["speedup"] = number(pcl_total / ours_total);
  }
#ifdef PRIMLABEL_HAVE_PCL
  if (args.compare_pcl) line["pcl_version"] = bench::pcl_tabletop_version();
#endif
  std::printf("%s\n", json::dump(line).c_str());
  return primlabel::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Milliseconds per scene of the table-top pre-filter, optionally against PCL."};
  app.set_version_flag("--version", primlabel::version_line("primlabel-bench-tabletop"));
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.name("primlabel-bench-tabletop");
  Arguments args;
  app.add_option("inputs", args.inputs, "scans (.pcd or .ply)")->required();
  app.add_flag("--compare-pcl", args.compare_pcl,
               "also time PCL's SACSegmentation + EuclideanClusterExtraction");
  app.add_option("--threads", args.threads, "threads for primlabel (PCL's steps are serial)")
      ->check(CLI::PositiveNumber);
  app.add_option("--repeat", args.repeat, "runs per scene; the fastest counts")
      ->check(CLI::PositiveNumber);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "primlabel-bench-tabletop: usage error: %s (see --help)\n", e.what());
    return primlabel::kExitUsage;
  }
#ifndef PRIMLABEL_HAVE_PCL
  if (args.compare_pcl) {
    std::fprintf(stderr, "primlabel-bench-tabletop: error: --compare-pcl needs PCL: %s\n",
                 primlabel::bench::pcl_unavailable_reason(
                     "PCL 1.13 with its segmentation and surface components")
                     .c_str());
    return primlabel::kExitFailure;
  }
#endif
  try {
    return run(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-bench-tabletop: error: %s\n", e.what());
    return primlabel::kExitFailure;
  }
}
