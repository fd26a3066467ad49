#pragma once
// What the throughput benchmarks (features, scaling) share: the fastest of several runs, and the
// finite points of a cloud, so that primlabel and its peers time exactly the same points.

#include <algorithm>
#include <chrono>
#include <functional>
#include <limits>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::bench {

// Runs `work` `repeat` times and returns the fastest wall time: the least disturbed by the other
// processes sharing the machine.
inline double best_seconds(int repeat, const std::function<void()>& work) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < std::max(1, repeat); ++r) {
    const auto start = std::chrono::steady_clock::now();
    work();
    best = std::min(
        best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

// The finite points of `cloud` as a new unorganised cloud (xyz and viewpoint only): both
// primlabel and a peer then work on exactly the same points, with no NaN handling in the way.
inline PointCloud finite_points(const PointCloud& cloud) {
  PointCloud out;
  out.viewpoint = cloud.viewpoint;
  out.xyz.reserve(cloud.size());
  for (const Vec3f& p : cloud.xyz)
    if (is_finite(p)) out.xyz.push_back(p);
  out.width = static_cast<std::uint32_t>(out.xyz.size());
  out.height = 1;
  return out;
}

}  // namespace primlabel::bench
