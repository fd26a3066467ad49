// primlabel-bench scaling: points/s of normals and FPFH against the thread count (1, 2, 4, 8, 16
// by default), with PCL's NormalEstimationOMP and FPFHEstimationOMP on the same points, normals
// and index kind in the same run when the build has PCL. With no input it times a synthetic
// LMS400 test scene, so it runs on any machine. Rows beyond the machine's hardware threads are
// oversubscribed and say so. Prints, never asserts; the last line is JSON.
//
//   primlabel-bench scaling                                   # synthetic LMS400, 1..16 threads
//   primlabel-bench scaling --input ../shared/data/mosd/learn0.pcd --threads 1,2 --repeat 3

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "bench_commands.hpp"
#include "bench_timing.hpp"
#include "pcl_availability.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/normals.hpp"
#include "primlabel/synth/generate.hpp"

#ifdef PRIMLABEL_HAVE_PCL
#include "pcl_peer.hpp"
#endif

namespace primlabel::bench {
namespace {

struct Arguments {
  std::string input;  // empty: the synthetic LMS400 test scene 0
  std::vector<int> threads = {1, 2, 4, 8, 16};
  float normal_radius = 0.01f, feature_radius = 0.025f;  // the LMS400 models' own
  int repeat = 3;
  bool skip_pcl = false;
};

struct Row {
  int threads = 0;
  double normals_pts_s = 0, fpfh_pts_s = 0;
  std::optional<double> pcl_normals_pts_s, pcl_fpfh_pts_s;
};

int run(const Arguments& args) {
  PointCloud cloud =
      finite_points(args.input.empty() ? synth::synthetic_scene(synth::SceneSet::kTest, 0,
                                                                synth::SensorKind::kLms400)
                                       : read_cloud(args.input));
  if (cloud.empty()) {
    std::cerr << "primlabel-bench scaling: no finite point in the input\n";
    return kExitUsage;
  }
  const std::size_t n = cloud.size();
  const unsigned hardware = std::thread::hardware_concurrency();
  const NeighborSearch search(cloud.xyz);
  NormalOptions normal_options;
  normal_options.neighborhood = Neighborhood::Radius(args.normal_radius);
  FeatureOptions feature_options;
  feature_options.neighborhood = Neighborhood::Radius(args.feature_radius);

  bool with_pcl = false;
#ifdef PRIMLABEL_HAVE_PCL
  std::optional<PclPeer> peer;
  if (!args.skip_pcl) peer.emplace(cloud.xyz), with_pcl = true;
#endif
  std::string no_pcl = args.skip_pcl ? "--skip-pcl" : "";
#ifndef PRIMLABEL_HAVE_PCL
  if (!args.skip_pcl) no_pcl = pcl_unavailable_reason("PCL 1.13 (common, features, kdtree)");
#endif
  std::cerr << (args.input.empty() ? "synthetic LMS400 test scene 0" : args.input) << ": " << n
            << " finite points; normals r = " << args.normal_radius
            << " m, FPFH r = " << args.feature_radius << " m; best of " << args.repeat
            << "; hardware threads " << hardware << "\n";
  if (!with_pcl) std::cerr << "PCL columns empty: " << no_pcl << "\n";

  std::vector<Row> rows;
  for (int threads : args.threads) {
    Row row;
    row.threads = threads;
    const RunContext context{threads};
    row.normals_pts_s = double(n) / best_seconds(args.repeat, [&] {
                          estimate_normals(cloud, normal_options, context, &search);
                        });
    row.fpfh_pts_s = double(n) / best_seconds(args.repeat, [&] {
                       compute_fpfh(cloud, feature_options, context, {.search = &search});
                     });
#ifdef PRIMLABEL_HAVE_PCL
    if (peer) {
      row.pcl_normals_pts_s =
          double(n) / peer->estimate_normals(normal_options.neighborhood, cloud.viewpoint.origin,
                                             threads, args.repeat)
                          .seconds;
      // On primlabel's normals: the comparison is of the descriptor alone.
      row.pcl_fpfh_pts_s =
          double(n) /
          peer->compute_fpfh(cloud.normals, feature_options.neighborhood, threads, args.repeat)
              .seconds;
    }
#endif
    rows.push_back(row);
  }

  std::printf("%7s %14s %8s %14s %8s %16s %16s %9s\n", "threads", "normals pts/s", "speedup",
              "FPFH pts/s", "speedup", "PCL normals pts/s", "PCL FPFH pts/s", "FPFH/PCL");
  json::Json out = json::Json::array();
  for (const Row& row : rows) {
    const Row& one = rows.front();
    const bool over = hardware > 0 && unsigned(row.threads) > hardware;
    char pcl[3][24] = {"-", "-", "-"};
    if (row.pcl_fpfh_pts_s) {
      std::snprintf(pcl[0], sizeof pcl[0], "%.0f", *row.pcl_normals_pts_s);
      std::snprintf(pcl[1], sizeof pcl[1], "%.0f", *row.pcl_fpfh_pts_s);
      std::snprintf(pcl[2], sizeof pcl[2], "%.1fx", row.fpfh_pts_s / *row.pcl_fpfh_pts_s);
    }
    std::printf("%7d %14.0f %7.2fx %14.0f %7.2fx %16s %16s %9s%s\n", row.threads, row.normals_pts_s,
                row.normals_pts_s / one.normals_pts_s, row.fpfh_pts_s,
                row.fpfh_pts_s / one.fpfh_pts_s, pcl[0], pcl[1], pcl[2],
                over ? "  (oversubscribed)" : "");
    json::Json item = {{"threads", row.threads},
                       {"normals_pts_s", json::rounded(row.normals_pts_s, "%.6g")},
                       {"fpfh_pts_s", json::rounded(row.fpfh_pts_s, "%.6g")},
                       {"oversubscribed", over}};
    item["pcl_normals_pts_s"] =
        row.pcl_normals_pts_s ? json::rounded(*row.pcl_normals_pts_s, "%.6g") : json::Json();
    item["pcl_fpfh_pts_s"] =
        row.pcl_fpfh_pts_s ? json::rounded(*row.pcl_fpfh_pts_s, "%.6g") : json::Json();
    out.push_back(item);
  }
  std::cout << json::dump(json::Json{{"bench", "scaling"},
                                     {"points", n},
                                     {"hardware_threads", hardware},
                                     {"rows", out}})
            << std::endl;
  return kExitOk;
}

}  // namespace

BenchCommand add_scaling_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "scaling", "Normals and FPFH points/s against the thread count, with PCL's OMP estimators.");
  cmd->add_option("--input", args->input, "cloud to time (default: synthetic LMS400 test scene 0)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--threads", args->threads, "thread counts (default 1,2,4,8,16)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  cmd->add_option("--normal-radius", args->normal_radius, "normal neighbourhood radius (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--feature-radius", args->feature_radius, "FPFH neighbourhood radius (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--repeat", args->repeat, "runs per case; the fastest counts")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--skip-pcl", args->skip_pcl, "leave PCL out even when the build has it");
  return {cmd, [args] { return run(*args); }};
}

}  // namespace primlabel::bench
