// primlabel-bench organised: issue 48's organised-frame path measured on real 640x480 frames at
// the served Kinect model's voxels. Per frame and radius, every voxel centroid's neighbour list by
// the radius grid (what the labeling path searches with) and by the image-plane grid
// (image_grid.hpp), with a check that the sets are equal; then the served PCA normals beside
// integral-image normals (integral_normals.hpp) carried to the voxels, and PCL's
// IntegralImageNormalEstimation in a build with PCL. One thread. Each stage is its own function,
// so one callgrind run gives every stage's instructions. With --model, the frame is also labeled
// as the service labels it (voxels, PCA normals, the plane cascade) and with integral-image
// normals per pixel instead (the cloud's own normals, their mean per voxel): how many labels
// differ, and with --truth (the frames' labels are classes, 0 unscored: write-truth's files)
// each one's accuracy.
//
//   primlabel-bench organised learn20.pcd learn5.pcd
//   primlabel-bench organised --model deploy/models/tabletop-kinect.plm --truth learn20_truth.pcd
//   valgrind --tool=callgrind primlabel-bench organised learn20.pcd --repeat 1 --skip-pcl
//   callgrind_annotate --inclusive=yes callgrind.out.* | grep organised_stage

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench_commands.hpp"
#include "bench_timing.hpp"
#include "image_grid.hpp"
#include "integral_normals.hpp"
#include "pcl_availability.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/neighbor_lists.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/normals.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

#ifdef PRIMLABEL_HAVE_PCL
#include "pcl_integral_normals.hpp"
#endif

namespace primlabel::bench {
namespace {

struct Arguments {
  std::vector<std::string> frames;
  float voxel_size = 0.007f;                  // the served tabletop-kinect model's
  std::vector<float> radii = {0.03f, 0.04f};  // its normal radius and its largest FPFH scale
  float normal_radius = 0.03f;
  int repeat = 3;
  bool skip_pcl = false;
  std::string model;   // label with it: the served path against integral-image normals
  bool truth = false;  // the frames' labels are taxonomy classes to score against
};

// The cap the labeling path puts on a radius search (pipeline::kDefaultMaxNeighbors).
constexpr int kCap = 1024;

// Lists stored flat, as NeighborLists keeps them.
struct Lists {
  std::vector<std::uint32_t> begin;
  std::vector<std::uint32_t> indices;
  std::vector<float> sq_dists;
  void clear(std::size_t points) {
    begin.assign(1, 0);
    begin.reserve(points + 1);
    indices.clear();
    sq_dists.clear();
  }
  void add(const NeighborList& found) {
    indices.insert(indices.end(), found.indices.begin(), found.indices.end());
    sq_dists.insert(sq_dists.end(), found.sq_dists.begin(), found.sq_dists.end());
    begin.push_back(std::uint32_t(indices.size()));
  }
};

// The radius grid's lists (its grid built on the first query, as in the labeling path).
[[gnu::noinline]] void organised_stage_radius_grid(const std::vector<Vec3f>& points, float radius,
                                                   Lists& out) {
  const NeighborSearch search(points);
  NeighborList found;
  out.clear(points.size());
  for (const Vec3f& p : points) {
    search.find(p, Neighborhood::Hybrid(radius, kCap), found, /*sorted=*/false);
    out.add(found);
  }
}

// The image grid's lists; `candidates` compared, queries it could not answer (`fallbacks`).
[[gnu::noinline]] void organised_stage_image_grid(const std::vector<Vec3f>& points,
                                                  const Viewpoint& viewpoint, float radius,
                                                  Lists& out, std::size_t& candidates,
                                                  std::size_t& fallbacks) {
  const std::unique_ptr<ImageGrid> grid = ImageGrid::build(points, radius, viewpoint);
  NeighborList found;
  out.clear(points.size());
  candidates = fallbacks = 0;
  for (const Vec3f& p : points) {
    found.clear();
    std::size_t compared = 0;
    if (!grid || !grid->find(p, radius, found, &compared)) ++fallbacks;
    candidates += compared;
    out.add(found);
  }
}

// The served normals: PCA over the shared lists (built apart, as the labeling path does).
[[gnu::noinline]] void organised_stage_pca_normals(PointCloud& voxels, const NeighborLists& lists,
                                                   float radius) {
  NormalOptions options;
  options.neighborhood = Neighborhood::Hybrid(radius, kCap);
  estimate_normals(voxels, options, RunContext{1}, nullptr, &lists);
}

[[gnu::noinline]] VoxelNormals organised_stage_integral_normals(
    const PointCloud& frame, const tabletop::VoxelGrid& voxels,
    const std::vector<std::uint32_t>& pixels, float radius, float focal) {
  const IntegralMoments moments(frame);
  return integral_voxel_normals(frame, moments, voxels, pixels, radius, focal);
}

// Lists with different sets, comparing each point's sorted indices.
std::size_t different_sets(const Lists& a, const Lists& b) {
  std::size_t different = 0;
  std::vector<std::uint32_t> x, y;
  for (std::size_t i = 0; i + 1 < a.begin.size(); ++i) {
    x.assign(a.indices.begin() + a.begin[i], a.indices.begin() + a.begin[i + 1]);
    y.assign(b.indices.begin() + b.begin[i], b.indices.begin() + b.begin[i + 1]);
    std::sort(x.begin(), x.end());
    std::sort(y.begin(), y.end());
    different += x != y;
  }
  return different;
}

struct AngleStats {
  std::size_t compared = 0;
  double median = NAN, p90 = NAN, over10 = NAN, over30 = NAN;  // degrees; shares in %
};

// Unsigned angles between two normal sets where both are finite.
AngleStats angles(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  std::vector<double> degrees;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (is_finite(a[i]) && is_finite(b[i]))
      degrees.push_back(std::acos(std::min(1.0f, std::fabs(a[i].dot(b[i])))) * 180.0 / M_PI);
  AngleStats stats;
  stats.compared = degrees.size();
  if (degrees.empty()) return stats;
  std::sort(degrees.begin(), degrees.end());
  const double n = double(degrees.size());
  stats.median = degrees[degrees.size() / 2];
  stats.p90 = degrees[degrees.size() * 9 / 10];
  stats.over10 =
      100.0 *
      double(std::count_if(degrees.begin(), degrees.end(), [](double d) { return d > 10.0; })) / n;
  stats.over30 =
      100.0 *
      double(std::count_if(degrees.begin(), degrees.end(), [](double d) { return d > 30.0; })) / n;
  return stats;
}

json::Json angle_json(const AngleStats& s) {
  return {{"compared", s.compared},
          {"median_deg", json::rounded(s.median, "%.3g")},
          {"p90_deg", json::rounded(s.p90, "%.3g")},
          {"over_10_deg_pct", json::rounded(s.over10, "%.3g")},
          {"over_30_deg_pct", json::rounded(s.over30, "%.3g")}};
}

void print_angles(const char* what, const AngleStats& s) {
  std::printf(
      "  %-44s median %5.2f deg, p90 %5.2f, > 10 deg %5.1f%%, > 30 deg %5.1f%% (%zu voxels)\n",
      what, s.median, s.p90, s.over10, s.over30, s.compared);
}

struct LabelAgreement {
  double equal_pct = 0;                 // of the finite points
  double accuracy_pct[2] = {NAN, NAN};  // served, integral normals; against the frame's labels
};

// The frame labeled as the service labels it, and with integral-image normals per pixel.
LabelAgreement compare_labels(const LabelModel& model, const PointCloud& frame,
                              const IntegralMoments& moments, float radius, float focal,
                              bool truth) {
  pipeline::LabelingOptions served;
  served.plane_cascade = true;  // the service's default (LabelOptions.every_point off)
  PointCloud copy = frame;
  const std::vector<std::uint32_t> by_pca = pipeline::label_cloud(model, copy, served).labels;
  copy = frame;
  copy.normals = integral_pixel_normals(frame, moments, radius, focal);
  pipeline::LabelingOptions own;
  own.use_cloud_normals = true;
  const std::vector<std::uint32_t> by_integral = pipeline::label_cloud(model, copy, own).labels;
  LabelAgreement out;
  std::size_t finite = 0, equal = 0, scored = 0, right[2] = {0, 0};
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (!is_finite(frame.xyz[i])) continue;
    ++finite;
    equal += by_pca[i] == by_integral[i];
    if (!truth || frame.labels.empty() || frame.labels[i] == 0) continue;
    ++scored;
    right[0] += by_pca[i] == frame.labels[i];
    right[1] += by_integral[i] == frame.labels[i];
  }
  out.equal_pct = finite ? 100.0 * double(equal) / double(finite) : NAN;
  for (int k = 0; k < 2 && scored > 0; ++k)
    out.accuracy_pct[k] = 100.0 * double(right[k]) / double(scored);
  return out;
}

int run(const Arguments& args) {
  std::optional<LabelModel> model;
  if (!args.model.empty()) model = load_model(args.model);
  bool with_pcl = false;
#ifdef PRIMLABEL_HAVE_PCL
  with_pcl = !args.skip_pcl;
#endif
  std::string no_pcl = args.skip_pcl ? "--skip-pcl" : "";
#ifndef PRIMLABEL_HAVE_PCL
  if (!args.skip_pcl) no_pcl = pcl_unavailable_reason("PCL 1.13 (common, features)");
#endif
  if (!with_pcl) std::cerr << "PCL IntegralImageNormalEstimation column empty: " << no_pcl << "\n";
  json::Json rows = json::Json::array();
  for (const std::string& path : args.frames) {
    const PointCloud frame = read_cloud(path);
    if (!frame.organized()) {
      std::cerr << "primlabel-bench organised: " << path << " is not an organised frame\n";
      return kExitUsage;
    }
    const tabletop::VoxelGrid grid =
        tabletop::voxel_downsample(frame.xyz, tabletop::finite_indices(frame.xyz), args.voxel_size);
    PointCloud voxels;
    voxels.resize_unorganized(grid.centroids.size());
    voxels.xyz = grid.centroids;
    voxels.viewpoint = frame.viewpoint;
    std::printf("%s: %zu voxels of %.0f mm (1 thread, best of %d)\n", path.c_str(), voxels.size(),
                args.voxel_size * 1000.0, args.repeat);
    json::Json row = {{"frame", path}, {"voxels", voxels.size()}};
    json::Json searches = json::Json::array();
    for (const float radius : args.radii) {
      Lists by_grid, by_image;
      std::size_t candidates = 0, fallbacks = 0;
      const double grid_s = best_seconds(
          args.repeat, [&] { organised_stage_radius_grid(voxels.xyz, radius, by_grid); });
      const double image_s = best_seconds(args.repeat, [&] {
        organised_stage_image_grid(voxels.xyz, frame.viewpoint, radius, by_image, candidates,
                                   fallbacks);
      });
      const std::size_t different = different_sets(by_grid, by_image);
      const std::size_t neighbours = by_grid.indices.size();
      std::printf(
          "  r = %2.0f mm: %zu neighbours; radius grid %6.2f ms, image grid %6.2f ms (%.2f "
          "candidates a neighbour, %zu queries left to the radius grid); different sets: %zu\n",
          radius * 1000.0, neighbours, grid_s * 1e3, image_s * 1e3,
          neighbours ? double(candidates) / double(neighbours) : 0.0, fallbacks, different);
      searches.push_back({{"radius", radius},
                          {"neighbours", neighbours},
                          {"radius_grid_ms", json::rounded(grid_s * 1e3, "%.4g")},
                          {"image_grid_ms", json::rounded(image_s * 1e3, "%.4g")},
                          {"image_candidates", candidates},
                          {"image_fallbacks", fallbacks},
                          {"different_sets", different}});
    }
    row["searches"] = searches;

    const NeighborSearch search(voxels.xyz);
    const NeighborLists lists(voxels.xyz, search, Neighborhood::Hybrid(args.normal_radius, kCap),
                              std::size_t(256) << 20);
    const double pca_s = best_seconds(
        args.repeat, [&] { organised_stage_pca_normals(voxels, lists, args.normal_radius); });
    const float focal = estimate_focal(frame);
    const std::vector<std::uint32_t> pixels = voxel_pixels(frame, grid);
    VoxelNormals integral;
    const double integral_s = best_seconds(args.repeat, [&] {
      integral = organised_stage_integral_normals(frame, grid, pixels, args.normal_radius, focal);
    });
    const AngleStats ours = angles(voxels.normals, integral.normals);
    std::printf(
        "  normals, r = %.0f mm (focal %.1f px): PCA on shared lists %.2f ms, integral "
        "images %.2f ms\n",
        args.normal_radius * 1000.0, focal, pca_s * 1e3, integral_s * 1e3);
    print_angles("integral-image vs served PCA normals:", ours);
    row["normals"] = {{"focal_px", json::rounded(focal, "%.5g")},
                      {"pca_ms", json::rounded(pca_s * 1e3, "%.4g")},
                      {"integral_ms", json::rounded(integral_s * 1e3, "%.4g")},
                      {"integral_vs_pca", angle_json(ours)}};
    json::Json pcl = json::Json();
#ifdef PRIMLABEL_HAVE_PCL
    if (with_pcl) {
      pcl = json::Json::object();
      for (const std::string method : {"average_3d_gradient", "covariance_matrix"}) {
        const PclPixelNormals peer = pcl_integral_normals(frame, method, args.repeat);
        std::vector<Vec3f> at_voxels(pixels.size());
        for (std::size_t v = 0; v < pixels.size(); ++v) at_voxels[v] = peer.normals[pixels[v]];
        const AngleStats theirs = angles(voxels.normals, at_voxels);
        std::printf("  PCL IntegralImageNormalEstimation (%s): %.2f ms for %zu pixels\n",
                    method.c_str(), peer.seconds * 1e3, peer.normals.size());
        print_angles("  its voxels' pixels vs served PCA normals:", theirs);
        pcl[method] = {{"ms", json::rounded(peer.seconds * 1e3, "%.4g")},
                       {"vs_pca", angle_json(theirs)}};
      }
    }
#endif
    if (!with_pcl) std::printf("  PCL IntegralImageNormalEstimation: - (%s)\n", no_pcl.c_str());
    row["pcl_integral_normals"] = pcl;
    if (model) {
      const LabelAgreement labels = compare_labels(*model, frame, IntegralMoments(frame),
                                                   args.normal_radius, focal, args.truth);
      std::printf("  labels (%s): %.2f%% of the points the same with integral-image normals",
                  args.model.c_str(), labels.equal_pct);
      if (args.truth)
        std::printf("; accuracy against the frame's labels %.3f%% served, %.3f%% integral",
                    labels.accuracy_pct[0], labels.accuracy_pct[1]);
      std::printf("\n");
      row["labels"] = {{"model", args.model},
                       {"equal_pct", json::rounded(labels.equal_pct, "%.4g")},
                       {"served_accuracy_pct", json::rounded(labels.accuracy_pct[0], "%.5g")},
                       {"integral_accuracy_pct", json::rounded(labels.accuracy_pct[1], "%.5g")}};
    }
    rows.push_back(row);
  }
  std::cout << json::dump(json::Json{{"bench", "organised"}, {"frames", rows}}) << "\n";
  return kExitOk;
}

}  // namespace

BenchCommand add_organised_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "organised",
      "Organised 640x480 frames at the served voxels: neighbour lists by the radius grid and by "
      "an image-plane grid, PCA against integral-image normals (and PCL's).");
  cmd->add_option("frames", args->frames, "organised frames (PCD)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--voxel-size", args->voxel_size, "voxel edge (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--radii", args->radii, "search radii (m)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  cmd->add_option("--normal-radius", args->normal_radius, "normal radius (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--repeat", args->repeat, "runs per stage; the fastest counts")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--skip-pcl", args->skip_pcl, "leave PCL out even when the build has it");
  cmd->add_option("--model", args->model,
                  "also label each frame with this model: served normals against integral ones")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--truth", args->truth,
                "with --model: the frames' labels are classes (0 unscored) to score against");
  return {cmd, [args] { return run(*args); }};
}

}  // namespace primlabel::bench
