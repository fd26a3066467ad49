#pragma once
// PCL as a peer for the benchmarks: the same normals and FPFH computed by PCL 1.13's OpenMP
// estimators, with timings. This interface is PCL-free; pcl_peer.cpp is the only translation unit
// that includes PCL headers, so the rest of the bench compiles without PCL.

#include <memory>
#include <string>
#include <vector>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::bench {

struct PclNormals {
  std::vector<Vec3f> normals;    // NaN where PCL could not estimate one
  std::vector<float> curvature;  // NaN likewise
  double seconds = 0.0;          // best of the repeats, k-d tree build excluded
};

struct PclFpfh {
  std::vector<float> descriptors;  // row-major size() x 33
  double seconds = 0.0;            // best of the repeats, k-d tree build excluded
};

// Holds one PCL copy of the points and a sorted pcl::search::KdTree built on it, shared by every
// estimator so that the index is built once (and timed separately), as on the primlabel side.
class PclPeer {
 public:
  // `points` must all be finite.
  explicit PclPeer(const std::vector<Vec3f>& points);
  ~PclPeer();
  PclPeer(const PclPeer&) = delete;
  PclPeer& operator=(const PclPeer&) = delete;

  double index_seconds() const;

  // pcl::NormalEstimationOMP. `hood` must be a pure radius or pure k-NN neighbourhood.
  PclNormals estimate_normals(const Neighborhood& hood, const Vec3f& viewpoint, int threads,
                              int repeat);

  // pcl::FPFHEstimationOMP on the given normals (one per point).
  PclFpfh compute_fpfh(const std::vector<Vec3f>& normals, const Neighborhood& hood, int threads,
                       int repeat);

  static std::string version();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace primlabel::bench
