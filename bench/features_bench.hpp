#pragma once
// `primlabel-bench features`: throughput and peak memory of normals -> FPFH -> PFH on one cloud,
// optionally against PCL 1.13 (normals and FPFH, with the largest differences).

#include <cstddef>
#include <cstdint>
#include <string>

namespace CLI {
class App;
}

namespace primlabel::bench {

struct FeaturesBenchOptions {
  std::string input;
  float normal_radius = 0.0f;  // exactly one of normal_radius / normal_k
  int normal_k = 0;
  float feature_radius = 0.0f;  // exactly one of feature_radius / feature_k
  int feature_k = 0;
  float voxel = 0.0f;  // > 0: voxel-grid downsample (centroid per voxel) before anything else
  // > 0: keep only the `crop` points nearest the centroid (after --voxel): a small cloud cut
  // out of a large one, where fixed costs weigh more.
  std::size_t crop = 0;
  // When set: the benchmarked points with primlabel's normals, as PLY (x y z nx ny nz), so
  // another library (bench/fpfh_peers.sh: Open3D) can be timed on exactly the same input.
  std::string write_cloud;
  int threads = 1;
  bool compare_pcl = false;
  std::string descriptor = "both";  // fpfh | pfh | both
  bool skip_pfh = false;
  int repeat = 1;  // every timed stage runs this many times; the fastest run counts
  // PFH is O(k^2) per point. Above this many point pairs on the full cloud, PFH is timed on a
  // stride subsample and its throughput extrapolated from the measured pair rate.
  double pfh_max_pairs = 4e8;
};

// Registers the `features` subcommand on `parent`, binding its flags to `options`.
CLI::App* add_features_command(CLI::App& parent, FeaturesBenchOptions& options);

// Runs the benchmark; returns the process exit code (0 ok, 1 failure, 2 bad usage).
int run_features_bench(const FeaturesBenchOptions& options);

}  // namespace primlabel::bench
