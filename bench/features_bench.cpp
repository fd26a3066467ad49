// `primlabel-bench features`: see features_bench.hpp and bench/README.md.

#include "features_bench.hpp"

#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <iostream>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "bench_timing.hpp"
#include "pcl_availability.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/normals.hpp"
#include "primlabel/geometry/parallel.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

#ifdef PRIMLABEL_HAVE_PCL
#include "pcl_peer.hpp"
#endif

namespace primlabel::bench {

namespace {

using Clock = std::chrono::steady_clock;

using primlabel::kExitOk;
using primlabel::kExitUsage;

// Points sampled (evenly spaced indices) to estimate neighbourhood sizes outside the timed runs.
constexpr std::size_t kNeighborhoodSamples = 2000;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

// One JSON object on one line (nlohmann-json), keys in insertion order. Numbers keep the 9
// significant digits the line has always had; non-finite ones become null.
class JsonLine {
 public:
  void add(const std::string& key, double value) { line_[key] = json::rounded(value, "%.9g"); }
  void add(const std::string& key, std::size_t value) { line_[key] = value; }
  void add(const std::string& key, int value) { line_[key] = value; }
  void add(const std::string& key, bool value) { line_[key] = value; }
  void add(const std::string& key, const std::string& value) { line_[key] = value; }
  void add_null(const std::string& key) { line_[key] = nullptr; }
  std::string str() const { return json::dump(line_); }

 private:
  json::Json line_ = json::Json::object();
};

// Evenly spaced indices 0, n/m, 2n/m, ... : at most `m` of them, the same on every run.
std::vector<std::size_t> stride_sample(std::size_t n, std::size_t m) {
  std::vector<std::size_t> indices;
  const std::size_t count = std::min(n, m);
  for (std::size_t i = 0; i < count; ++i) indices.push_back(i * n / count);
  return indices;
}

bool usable(const PointCloud& cloud, std::size_t i) {
  return is_finite(cloud.xyz[i]) && (!cloud.has_normals() || is_finite(cloud.normals[i]));
}

// Neighbourhood sizes as the descriptors see them: neighbours without a normal do not count.
struct NeighborhoodSizes {
  double mean_neighbors = 0.0;
  double mean_pfh_pairs = 0.0;  // k (k - 1) / 2 per point, 0 where PFH is NaN
  double total_pfh_pairs = 0.0;
};

NeighborhoodSizes measure_neighborhoods(const PointCloud& cloud, const NeighborSearch& search,
                                        const Neighborhood& hood,
                                        const std::vector<std::size_t>& points) {
  NeighborhoodSizes sizes;
  if (points.empty()) return sizes;
  NeighborList neighbors;
  for (std::size_t i : points) {
    if (!usable(cloud, i)) continue;
    search.find(cloud.xyz[i], hood, neighbors, /*sorted=*/false);  // only counted
    double k = 0;
    for (std::uint32_t j : neighbors.indices) k += usable(cloud, j) ? 1 : 0;
    sizes.mean_neighbors += k;
    if (k >= 2) sizes.total_pfh_pairs += k * (k - 1) / 2;
  }
  sizes.mean_neighbors /= static_cast<double>(points.size());
  sizes.mean_pfh_pairs = sizes.total_pfh_pairs / static_cast<double>(points.size());
  return sizes;
}

std::string describe(const Neighborhood& hood) {
  char buffer[64];
  if (hood.k > 0)
    std::snprintf(buffer, sizeof(buffer), "k=%d", hood.k);
  else
    std::snprintf(buffer, sizeof(buffer), "r=%g", hood.radius);
  return buffer;
}

std::string rate(double points, double seconds) {
  char buffer[96];
  std::snprintf(buffer, sizeof(buffer), "%.3f s, %.0f pts/s", seconds, points / seconds);
  return buffer;
}

struct PfhRun {
  double pts_s = 0.0;
  double seconds = 0.0;  // of the timed run
  bool extrapolated = false;
  std::size_t timed_points = 0;
  double pairs_per_s = 0.0;
  FeatureStats stats;
};

// PFH costs k (k - 1) / 2 pair features per point. When the full cloud would exceed
// `max_pairs`, PFH is timed on an evenly spaced subsample (a thinner cloud, so smaller
// neighbourhoods) and the full-cloud throughput is extrapolated from the measured pair rate and
// the full cloud's mean pair count. The API computes every point of the cloud it is given, so a
// query subset with full-cloud neighbourhoods cannot be timed directly.
PfhRun run_pfh(const PointCloud& cloud, const NeighborSearch& search, const FeatureOptions& options,
               const RunContext& context, const NeighborhoodSizes& full_sizes, double max_pairs,
               int repeat) {
  PfhRun run;
  const double n = static_cast<double>(cloud.size());
  const double full_pairs = full_sizes.mean_pfh_pairs * n;
  if (full_pairs <= max_pairs) {
    run.seconds = best_seconds(repeat, [&] {
      compute_pfh(cloud, options, context, {.search = &search, .stats = &run.stats});
    });
    run.pts_s = n / run.seconds;
    run.timed_points = cloud.size();
    run.pairs_per_s = full_pairs / run.seconds;
    return run;
  }

  // Radius neighbourhoods thin with the cloud (pairs ~ stride^-3); k-NN ones do not (~ stride^-1).
  const double excess = full_pairs / max_pairs;
  const double stride_real = options.neighborhood.k > 0 ? excess : std::cbrt(excess);
  const auto stride = static_cast<std::size_t>(std::ceil(stride_real));
  PointCloud thinned;
  thinned.viewpoint = cloud.viewpoint;
  for (std::size_t i = 0; i < cloud.size(); i += stride) {
    thinned.xyz.push_back(cloud.xyz[i]);
    thinned.normals.push_back(cloud.normals[i]);
  }
  thinned.width = static_cast<std::uint32_t>(thinned.xyz.size());
  const NeighborSearch thinned_search(thinned.xyz);
  run.seconds = best_seconds(repeat, [&] {
    compute_pfh(thinned, options, context, {.search = &thinned_search, .stats = &run.stats});
  });
  const NeighborhoodSizes thinned_sizes = measure_neighborhoods(
      thinned, thinned_search, options.neighborhood, stride_sample(thinned.size(), thinned.size()));
  run.extrapolated = true;
  run.timed_points = thinned.size();
  run.pairs_per_s = thinned_sizes.total_pfh_pairs / run.seconds;
  run.pts_s = run.pairs_per_s / full_sizes.mean_pfh_pairs;
  std::cerr << "  PFH on the full cloud would take ~" << full_pairs << " pair features (> "
            << max_pairs << "): timed on every " << stride << "th point (" << thinned.size()
            << " points, mean " << thinned_sizes.mean_neighbors << " neighbours, "
            << thinned_sizes.total_pfh_pairs << " pairs) in " << run.seconds
            << " s; full-cloud pts/s extrapolated from the pair rate (" << run.pairs_per_s
            << " pairs/s) and the full cloud's mean " << full_sizes.mean_pfh_pairs
            << " pairs per point\n";
  return run;
}

#ifdef PRIMLABEL_HAVE_PCL
// Two outputs "agree" on a point when no component differs by more than this.
constexpr double kDiffTolerance = 1e-3;

// Largest difference between two row-major tables over rows where both are finite; rows where
// exactly one side is non-finite are counted apart, rows non-finite on both sides are skipped.
struct RowComparison {
  double max_abs_diff = 0.0;
  std::size_t nan_mismatch = 0;
  std::size_t rows_over_tolerance = 0;
  std::size_t compared = 0;
  std::size_t worst_row = 0;
  std::size_t worst_column = 0;
};

// `skip` (optional, one flag per row) leaves rows out entirely.
RowComparison compare_rows(const float* ours, const float* theirs, std::size_t rows,
                           std::size_t columns, const std::vector<char>* skip = nullptr) {
  RowComparison result;
  const auto finite_row = [columns](const float* row) {
    return std::all_of(row, row + columns, [](float v) { return std::isfinite(v); });
  };
  for (std::size_t r = 0; r < rows; ++r) {
    if (skip && (*skip)[r]) continue;
    const float* a = ours + r * columns;
    const float* b = theirs + r * columns;
    const bool a_ok = finite_row(a), b_ok = finite_row(b);
    if (!a_ok || !b_ok) {
      result.nan_mismatch += a_ok != b_ok ? 1 : 0;
      continue;
    }
    ++result.compared;
    double row_max = 0.0;
    for (std::size_t c = 0; c < columns; ++c) {
      const double diff = std::abs(static_cast<double>(a[c]) - static_cast<double>(b[c]));
      if (diff > result.max_abs_diff) {
        result.max_abs_diff = diff;
        result.worst_row = r;
        result.worst_column = c;
      }
      row_max = std::max(row_max, diff);
    }
    result.rows_over_tolerance += row_max > kDiffTolerance ? 1 : 0;
  }
  return result;
}

void print_comparison(const std::string& what, const RowComparison& cmp, const float* ours,
                      const float* theirs, std::size_t columns) {
  std::cerr << "  " << what << " vs PCL: max |diff| " << cmp.max_abs_diff << " over "
            << cmp.compared << " points; " << cmp.rows_over_tolerance << " points differ by > "
            << kDiffTolerance << "; " << cmp.nan_mismatch << " points NaN on one side only\n";
  if (cmp.max_abs_diff > 0) {
    const std::size_t at = cmp.worst_row * columns + cmp.worst_column;
    std::cerr << "    worst: point " << cmp.worst_row << " component " << cmp.worst_column
              << ": primlabel " << ours[at] << ", PCL " << theirs[at] << "\n";
  }
}

// Flags the points whose FPFH depends on a point without a normal. There primlabel leaves that
// point out while PCL bins its NaN angles into bin 0 (a documented difference), so the FPFH
// comparison is also reported without these points. The dependence reaches two hops: FPFH(p)
// sums the SPFHs of p's neighbours, and each SPFH(q) reads q's neighbours.
std::vector<char> near_missing_normals(const PointCloud& cloud, const NeighborSearch& search,
                                       const Neighborhood& hood, int threads) {
  std::vector<char> missing(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) missing[i] = !is_finite(cloud.normals[i]);
  if (std::none_of(missing.begin(), missing.end(), [](char m) { return m != 0; })) return missing;
  const auto count = static_cast<std::ptrdiff_t>(cloud.size());
  const auto spread = [&](const std::vector<char>& seeds) {
    std::vector<char> reached(cloud.size(), 0);
    detail::parallel_for(
        count, threads, detail::Schedule::Dynamic(256), [] { return NeighborList{}; },
        [&](NeighborList& neighbors, std::ptrdiff_t i) {
          search.find(cloud.xyz[i], hood, neighbors, /*sorted=*/false);
          reached[i] = std::any_of(neighbors.indices.begin(), neighbors.indices.end(),
                                   [&](std::uint32_t j) { return seeds[j] != 0; });
        });
    return reached;
  };
  return spread(spread(missing));  // SPFH touched, then FPFH touched
}
#endif  // PRIMLABEL_HAVE_PCL

std::optional<Neighborhood> neighborhood_from(float radius, int k, const char* flag_prefix) {
  if ((radius > 0.0f) == (k > 0)) {
    std::cerr << "primlabel-bench features: give exactly one of --" << flag_prefix
              << "-radius and --" << flag_prefix << "-k\n";
    return std::nullopt;
  }
  return k > 0 ? Neighborhood::Knn(k) : Neighborhood::Radius(radius);
}

}  // namespace

CLI::App* add_features_command(CLI::App& parent, FeaturesBenchOptions& options) {
  CLI::App* cmd = parent.add_subcommand(
      "features", "Throughput of normals, FPFH and PFH on one cloud, optionally against PCL");
  cmd->add_option("input", options.input, "point cloud (.pcd or .ply)")
      ->required()
      ->check(CLI::ExistingFile);
  auto* normal_radius = cmd->add_option("--normal-radius", options.normal_radius,
                                        "radius of the normal-estimation neighbourhood");
  cmd->add_option("--normal-k", options.normal_k, "k-NN normal neighbourhood instead")
      ->excludes(normal_radius);
  auto* feature_radius = cmd->add_option("--feature-radius", options.feature_radius,
                                         "radius of the FPFH/PFH neighbourhood");
  cmd->add_option("--feature-k", options.feature_k, "k-NN FPFH/PFH neighbourhood instead")
      ->excludes(feature_radius);
  cmd->add_option("--voxel", options.voxel, "voxel-grid downsample (centroids) first; 0 = off")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--crop", options.crop,
                  "keep only the N points nearest the centroid (after --voxel); 0 = all");
  cmd->add_option("--write-cloud", options.write_cloud,
                  "write the benchmarked points with primlabel's normals here (.ply)");
  cmd->add_option("--threads", options.threads, "threads for every stage, primlabel and PCL")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--compare-pcl", options.compare_pcl,
                "also run PCL's NormalEstimationOMP and FPFHEstimationOMP and compare");
  cmd->add_option("--descriptor", options.descriptor, "descriptors to time")
      ->check(CLI::IsMember({"fpfh", "pfh", "both"}))
      ->capture_default_str();
  cmd->add_flag("--skip-pfh", options.skip_pfh, "do not time PFH");
  cmd->add_option("--repeat", options.repeat, "runs per timed stage; the fastest counts")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--pfh-max-pairs", options.pfh_max_pairs,
                  "above this many PFH pair features, time PFH on a subsample and extrapolate")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  return cmd;
}

int run_features_bench(const FeaturesBenchOptions& options) {
  const std::optional<Neighborhood> normal_hood =
      neighborhood_from(options.normal_radius, options.normal_k, "normal");
  const std::optional<Neighborhood> feature_hood =
      neighborhood_from(options.feature_radius, options.feature_k, "feature");
  if (!normal_hood || !feature_hood) return kExitUsage;
#ifndef PRIMLABEL_HAVE_PCL
  if (options.compare_pcl) {
    std::cerr << "primlabel-bench features: --compare-pcl needs PCL: "
              << pcl_unavailable_reason("PCL 1.13 (common, features, kdtree, search, io)") << "\n";
    return kExitUsage;
  }
#endif
  const bool run_fpfh = options.descriptor != "pfh";
  const bool run_pfh_stage = options.descriptor != "fpfh" && !options.skip_pfh;
  const int threads = options.threads;

  // --- Input --------------------------------------------------------------------------------
  auto start = Clock::now();
  const PointCloud raw = read_cloud(options.input);
  PointCloud cloud = finite_points(raw);
  const double load_seconds = seconds_since(start);
  std::cerr << options.input << ": " << raw.size() << " points, " << cloud.size()
            << " finite (read in " << load_seconds << " s; peak RSS " << peak_rss_mb() << " MB)\n";
  if (options.voxel > 0.0f) {
    // The input holds finite points only (dropped above), so every point takes part.
    std::vector<std::uint32_t> all(cloud.size());
    std::iota(all.begin(), all.end(), 0u);
    cloud.xyz = tabletop::voxel_downsample(cloud.xyz, all, options.voxel).centroids;
    cloud.width = static_cast<std::uint32_t>(cloud.size());
    std::cerr << "voxel " << options.voxel << ": " << cloud.size() << " points\n";
  }
  if (options.crop > 0 && options.crop < cloud.size()) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Vec3f& p : cloud.xyz) sum += p.cast<double>();
    const Vec3f centroid = (sum / double(cloud.size())).cast<float>();
    NeighborList nearest;
    NeighborSearch(cloud.xyz).find(centroid, Neighborhood::Knn(int(options.crop)), nearest);
    std::vector<std::uint32_t> kept = nearest.indices;
    std::sort(kept.begin(), kept.end());  // the file's order, not the distance order
    std::vector<Vec3f> cropped;
    for (std::uint32_t i : kept) cropped.push_back(cloud.xyz[i]);
    cloud.xyz = std::move(cropped);
    cloud.width = static_cast<std::uint32_t>(cloud.size());
    std::cerr << "crop: the " << cloud.size() << " points nearest the centroid\n";
  }
  if (cloud.empty()) throw std::runtime_error("no finite points in " + options.input);
  const std::size_t n = cloud.size();
  const Vec3f viewpoint = cloud.viewpoint.origin;

  // --- primlabel ----------------------------------------------------------------------------
  start = Clock::now();
  const NeighborSearch search(cloud.xyz);
  const double index_seconds = seconds_since(start);
  std::cerr << "primlabel, " << threads << " thread(s); k-d tree built in " << index_seconds
            << " s (not included in the stage times)\n";

  const std::vector<std::size_t> sample = stride_sample(n, kNeighborhoodSamples);
  const NeighborhoodSizes normal_sizes = measure_neighborhoods(cloud, search, *normal_hood, sample);

  NormalOptions normal_options;
  normal_options.neighborhood = *normal_hood;
  normal_options.viewpoint = viewpoint;
  NormalStats normal_stats;
  const double normals_seconds = best_seconds(options.repeat, [&] {
    normal_stats = estimate_normals(cloud, normal_options, RunContext{threads}, &search);
  });
  std::cerr << "  normals (" << describe(*normal_hood) << ", mean " << normal_sizes.mean_neighbors
            << " neighbours): " << rate(n, normals_seconds) << "; " << normal_stats.estimated
            << " estimated, " << normal_stats.too_few << " with too few neighbours; peak RSS "
            << peak_rss_mb() << " MB\n";

  // Feature neighbourhoods are measured after the normals exist: points without one drop out.
  const NeighborhoodSizes feature_sizes =
      measure_neighborhoods(cloud, search, *feature_hood, sample);
  FeatureOptions feature_options;
  feature_options.neighborhood = *feature_hood;

  Descriptors fpfh;
  FeatureStats fpfh_stats;
  double fpfh_seconds = std::numeric_limits<double>::quiet_NaN();
  if (run_fpfh) {
    fpfh_seconds = best_seconds(options.repeat, [&] {
      fpfh = compute_fpfh(cloud, feature_options, RunContext{threads},
                          {.search = &search, .stats = &fpfh_stats});
    });
    std::cerr << "  FPFH (" << describe(*feature_hood) << ", mean " << feature_sizes.mean_neighbors
              << " neighbours): " << rate(n, fpfh_seconds) << "; " << fpfh_stats.nan << " NaN, "
              << fpfh_stats.isolated << " isolated (all-zero) descriptors; peak RSS "
              << peak_rss_mb() << " MB\n";
  }

  std::optional<PfhRun> pfh;
  if (run_pfh_stage) {
    pfh = run_pfh(cloud, search, feature_options, RunContext{threads}, feature_sizes,
                  options.pfh_max_pairs, options.repeat);
    std::cerr << "  PFH (" << describe(*feature_hood) << "): " << pfh->pts_s << " pts/s"
              << (pfh->extrapolated ? " (extrapolated, see above)" : "") << "; " << pfh->stats.nan
              << " NaN, " << pfh->stats.isolated
              << " isolated descriptors in the timed run; peak RSS " << peak_rss_mb() << " MB\n";
  }

  const double rss_mb = peak_rss_mb();
  if (!options.write_cloud.empty()) {
    PointCloud out;
    out.resize_unorganized(n);
    out.xyz = cloud.xyz;
    out.normals = cloud.normals;
    out.viewpoint = cloud.viewpoint;
    write_ply(options.write_cloud, out);
    std::cerr << "wrote the " << n << " points and their normals to " << options.write_cloud
              << "\n";
  }

  JsonLine json;
  json.add("points", n);
  json.add("threads", threads);
  json.add("normals_pts_s", n / normals_seconds);
  json.add("fpfh_pts_s", n / fpfh_seconds);
  if (pfh)
    json.add("pfh_pts_s", pfh->pts_s);
  else
    json.add_null("pfh_pts_s");
  json.add("peak_rss_mb", rss_mb);

  // --- PCL ----------------------------------------------------------------------------------
#ifdef PRIMLABEL_HAVE_PCL
  if (options.compare_pcl) {
    std::cerr << "PCL " << PclPeer::version() << ", " << threads << " thread(s)\n";
    PclPeer peer(cloud.xyz);
    std::cerr << "  k-d tree built in " << peer.index_seconds()
              << " s (not included in the stage times)\n";

    const PclNormals pcl_normals =
        peer.estimate_normals(*normal_hood, viewpoint, threads, options.repeat);
    std::cerr << "  NormalEstimationOMP: " << rate(n, pcl_normals.seconds) << "\n";
    const RowComparison normal_cmp =
        compare_rows(cloud.normals.data()->data(), pcl_normals.normals.data()->data(), n, 3);
    print_comparison("normals", normal_cmp, cloud.normals.data()->data(),
                     pcl_normals.normals.data()->data(), 3);
    const RowComparison curvature_cmp =
        compare_rows(cloud.curvature.data(), pcl_normals.curvature.data(), n, 1);
    print_comparison("curvature", curvature_cmp, cloud.curvature.data(),
                     pcl_normals.curvature.data(), 1);

    json.add("pcl_normals_pts_s", n / pcl_normals.seconds);
    if (run_fpfh) {
      // PCL gets primlabel's normals, so the comparison isolates the descriptor.
      const PclFpfh pcl_fpfh =
          peer.compute_fpfh(cloud.normals, *feature_hood, threads, options.repeat);
      std::cerr << "  FPFHEstimationOMP on primlabel's normals: " << rate(n, pcl_fpfh.seconds)
                << "\n";
      const RowComparison fpfh_cmp =
          compare_rows(fpfh.values.data(), pcl_fpfh.descriptors.data(), n, kFpfhSize);
      print_comparison("FPFH", fpfh_cmp, fpfh.values.data(), pcl_fpfh.descriptors.data(),
                       kFpfhSize);
      const std::vector<char> near_missing =
          near_missing_normals(cloud, search, *feature_hood, threads);
      const auto near_missing_count =
          static_cast<std::size_t>(std::count(near_missing.begin(), near_missing.end(), 1));
      const RowComparison clean_cmp = compare_rows(fpfh.values.data(), pcl_fpfh.descriptors.data(),
                                                   n, kFpfhSize, &near_missing);
      if (near_missing_count > 0)
        print_comparison("FPFH without the " + std::to_string(near_missing_count) +
                             " points within two hops of a missing normal",
                         clean_cmp, fpfh.values.data(), pcl_fpfh.descriptors.data(), kFpfhSize);
      std::cerr << "  speedup (PCL time / primlabel time): normals "
                << pcl_normals.seconds / normals_seconds << "x, FPFH "
                << pcl_fpfh.seconds / fpfh_seconds << "x\n";
      json.add("pcl_fpfh_pts_s", n / pcl_fpfh.seconds);
      json.add("fpfh_max_abs_diff", fpfh_cmp.max_abs_diff);
      json.add("fpfh_nan_mismatch", fpfh_cmp.nan_mismatch);
      json.add("fpfh_points_off", fpfh_cmp.rows_over_tolerance);
      json.add("fpfh_near_missing_normals", near_missing_count);
      json.add("fpfh_max_abs_diff_clean", clean_cmp.max_abs_diff);
      json.add("fpfh_nan_mismatch_clean", clean_cmp.nan_mismatch);
      json.add("fpfh_points_off_clean", clean_cmp.rows_over_tolerance);
      json.add("fpfh_speedup", pcl_fpfh.seconds / fpfh_seconds);
    }
    json.add("normals_max_abs_diff", normal_cmp.max_abs_diff);
    json.add("normals_nan_mismatch", normal_cmp.nan_mismatch);
    json.add("normals_points_off", normal_cmp.rows_over_tolerance);
    json.add("curvature_max_abs_diff", curvature_cmp.max_abs_diff);
    json.add("normals_speedup", pcl_normals.seconds / normals_seconds);
    json.add("pcl_index_s", peer.index_seconds());
    json.add("diff_tolerance", kDiffTolerance);
  }
#endif

  // --- Context ------------------------------------------------------------------------------
  json.add("file", options.input);
  json.add("input_points", raw.size());
  json.add("voxel", static_cast<double>(options.voxel));
  json.add("crop", options.crop);
  if (normal_hood->k > 0)
    json.add("normal_k", normal_hood->k);
  else
    json.add("normal_radius", static_cast<double>(normal_hood->radius));
  if (feature_hood->k > 0)
    json.add("feature_k", feature_hood->k);
  else
    json.add("feature_radius", static_cast<double>(feature_hood->radius));
  json.add("avg_normal_neighbors", normal_sizes.mean_neighbors);
  json.add("avg_neighbors", feature_sizes.mean_neighbors);
  json.add("index_s", index_seconds);
  json.add("normals_s", normals_seconds);
  json.add("fpfh_s", fpfh_seconds);
  if (pfh) {
    json.add("pfh_s", pfh->seconds);
    json.add("pfh_extrapolated", pfh->extrapolated);
    json.add("pfh_timed_points", pfh->timed_points);
    json.add("pfh_pairs_per_s", pfh->pairs_per_s);
  }
  json.add("repeat", options.repeat);

  std::cout << json.str() << std::endl;
  return kExitOk;
}

}  // namespace primlabel::bench
