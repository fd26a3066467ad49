// primlabel-features: normals and FPFH/PFH descriptors for a point cloud file, offline.
//
//   primlabel-features scan.pcd -o scan_features.pcd --normal-radius 0.015 --feature-radius 0.03
//   primlabel-features scan.pcd --signature   # what a server routes a model-less request by

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <optional>

#include "primlabel/build_version.hpp"
#include "primlabel/cli/cli_common.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/cloud_signature.hpp"
#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/normals.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string input, output;
  int normal_k = 0, feature_k = 0, max_neighbors = 0, threads = 0;
  float normal_radius = 0, feature_radius = 0;
  std::string descriptor = "fpfh", variant = "pcl", viewpoint;
  bool use_input_normals = false, quiet = false, signature = false;
};

// One JSON line: the cloud's shape and its signature as acquired (geometry/cloud_signature.hpp),
// which a server compares with each model's training domain for a request naming no model.
int print_signature(const Arguments& args) {
  const PointCloud cloud = read_cloud(args.input);
  const Vec3f viewpoint =
      args.viewpoint.empty() ? cloud.viewpoint.origin : cli::parse_vec3(args.viewpoint);
  const CloudSignature s = measure_signature(cloud.xyz, viewpoint, RunContext{args.threads});
  json::Json out;
  out["file"] = args.input;
  out["points"] = cloud.size();
  out["width"] = cloud.organized() ? cloud.width : 0;
  out["height"] = cloud.organized() ? cloud.height : 0;
  out["point_spacing_m"] = json::rounded(s.point_spacing, "%.6f");
  out["roughness_m"] = json::rounded(s.roughness, "%.6f");
  out["noise_growth"] = json::rounded(s.noise_growth, "%.3f");
  out["depth_ties"] = json::rounded(s.depth_ties, "%.3f");
  std::printf("%s\n", json::dump(out).c_str());
  return cli::kExitOk;
}

// The K of --normal-k and --feature-k when neither that nor the radius is given.
constexpr int kDefaultNeighbors = 10;

// --NAME-k and --NAME-radius: `what` from the K nearest points or from those within R, not both.
// 0 stands for "not given"; --help shows what is used then.
void add_neighborhood_options(CLI::App& app, const std::string& name, const std::string& what,
                              int& k, float& radius) {
  CLI::Option* k_option = app.add_option("--" + name + "-k", k, what + " from the K nearest points")
                              ->check(CLI::PositiveNumber)
                              ->default_str(std::to_string(kDefaultNeighbors));
  app.add_option("--" + name + "-radius", radius, what + " from points within R")
      ->check(CLI::PositiveNumber)
      ->default_str("")
      ->excludes(k_option);
}

Neighborhood neighborhood_of(int k, float radius, int max_neighbors, int default_k) {
  if (radius > 0)
    return max_neighbors > 0 ? Neighborhood::Hybrid(radius, max_neighbors)
                             : Neighborhood::Radius(radius);
  return Neighborhood::Knn(k > 0 ? k : default_k);
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int run(const Arguments& args) {
  if (args.signature) return print_signature(args);
  cli::ProgressPrinter progress(args.quiet);
  PointCloud cloud = read_cloud(args.input);
  const std::size_t finite = count_finite(cloud);
  if (finite == 0) {
    std::fprintf(stderr, "primlabel-features: error: %s: no point has finite coordinates\n",
                 args.input.c_str());
    return cli::kExitFailure;
  }
  NeighborSearch search(cloud.xyz);

  const auto normals_start = std::chrono::steady_clock::now();
  if (args.use_input_normals) {
    if (!cloud.has_normals()) {
      std::fprintf(stderr,
                   "primlabel-features: error: %s has no normal_x/normal_y/normal_z fields "
                   "(--use-input-normals)\n",
                   args.input.c_str());
      return cli::kExitFailure;
    }
  } else {
    NormalOptions options;
    options.neighborhood =
        neighborhood_of(args.normal_k, args.normal_radius, args.max_neighbors, kDefaultNeighbors);
    if (!args.viewpoint.empty()) options.viewpoint = cli::parse_vec3(args.viewpoint);
    const NormalStats stats = estimate_normals(
        cloud, options, RunContext{args.threads, {}, progress.stage("normals")}, &search);
    progress.done();
    if (!args.quiet)
      std::fprintf(stderr, "normals: %zu estimated, %zu with too few neighbours (NaN), %.2f s\n",
                   stats.estimated, stats.too_few, seconds_since(normals_start));
  }

  FeatureOptions options;
  options.neighborhood =
      neighborhood_of(args.feature_k, args.feature_radius, args.max_neighbors, kDefaultNeighbors);
  options.fpfh_variant = args.variant == "paper" ? FpfhVariant::kWithOwnSpfh : FpfhVariant::kPcl;
  const RunContext context{args.threads, {}, progress.stage(args.descriptor)};
  const auto features_start = std::chrono::steady_clock::now();
  FeatureStats stats;
  const bool fpfh = args.descriptor == "fpfh";
  const FeatureExtras extras{.search = &search, .stats = &stats};
  Descriptors descriptors = fpfh ? compute_fpfh(cloud, options, context, extras)
                                 : compute_pfh(cloud, options, context, extras);
  progress.done();
  const double feature_seconds = seconds_since(features_start);
  FloatField& field =
      cloud.set_field(fpfh ? fpfh_field_name(options.fpfh_variant) : "pfh", descriptors.dim);
  field.values = std::move(descriptors.values);

  write_cloud(args.output, cloud);
  if (!args.quiet)
    std::fprintf(stderr,
                 "%s: %zu computed, %zu isolated (all zero), %zu invalid (NaN), %.2f s "
                 "(%.0f points/s); wrote %s\n",
                 args.descriptor.c_str(), stats.computed, stats.isolated, stats.nan,
                 feature_seconds, double(cloud.size()) / std::max(feature_seconds, 1e-9),
                 args.output.c_str());
  return cli::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Estimate normals and FPFH/PFH descriptors for every point of a PCD/PLY cloud."};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-features"));
  app.name("primlabel-features");
  Arguments args;
  app.add_option("input", args.input, "input cloud (.pcd or .ply)")->required();
  auto* output = app.add_option("-o,--output", args.output, "output cloud (.pcd or .ply)");
  app.add_flag("--signature", args.signature,
               "print the cloud's signature (point spacing, roughness, noise growth with range: "
               "what a server picks a model by) as one JSON line instead")
      ->excludes(output);
  add_neighborhood_options(app, "normal", "normals", args.normal_k, args.normal_radius);
  add_neighborhood_options(app, "feature", "descriptors", args.feature_k, args.feature_radius);
  app.add_option("--max-neighbors", args.max_neighbors,
                 "cap radius neighbourhoods at the M nearest points")
      ->check(CLI::PositiveNumber)
      ->default_str("none");
  app.add_option("--descriptor", args.descriptor, "fpfh (33 bins) or pfh (125 bins)")
      ->check(CLI::IsMember({"fpfh", "pfh"}));
  app.add_option("--fpfh-variant", args.variant,
                 "pcl: as PCL computes it; paper: also add the point's own SPFH (as Open3D)")
      ->check(CLI::IsMember({"pcl", "paper"}));
  app.add_flag("--use-input-normals", args.use_input_normals,
               "use the normals stored in the input instead of estimating them");
  app.add_option("--viewpoint", args.viewpoint,
                 "X,Y,Z the normals face (default: the file's VIEWPOINT)");
  app.add_option("--threads", args.threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  app.add_flag("-q,--quiet", args.quiet, "no progress or summary on stderr");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "primlabel-features: usage error: %s (see --help)\n", e.what());
    return cli::kExitUsage;
  }
  if (args.output.empty() && !args.signature) {
    std::fprintf(stderr, "primlabel-features: usage error: --output is required (see --help)\n");
    return cli::kExitUsage;
  }
  if (args.use_input_normals && (args.normal_k > 0 || args.normal_radius > 0)) {
    std::fprintf(stderr,
                 "primlabel-features: usage error: --use-input-normals excludes --normal-k and "
                 "--normal-radius\n");
    return cli::kExitUsage;
  }
  try {
    return run(args);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "primlabel-features: usage error: %s\n", e.what());
    return cli::kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-features: error: %s\n", e.what());
    return cli::kExitFailure;
  }
}
