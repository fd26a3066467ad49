#pragma once
// Clusters that are only the table seen through depth noise. A Kinect's depth error grows with
// the square of the range (docs/results.md "Kinect calibration": sigma = 2.82e-3 z^2 m to the
// frame's plane, levels z^2 / 345 m apart), so at 1.5 m the table's far end scatters beyond any
// fixed table band and leaves flat patches that Euclidean clustering counts as objects. A cluster
// is table noise when nearly all of its points lie within the noise band of their own range; such
// points cannot be told from the table and are given to it. So are points below the table within
// that band (nothing stands below the table).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::tabletop {

struct TableNoiseOptions {
  bool enabled = true;
  float depth_noise_per_m2 = 2.82e-3f;  // depth sigma / range^2 (1/m), the Kinect's, measured
  float noise_sigmas = 3.0f;            // band: |height| <= this many sigmas at the point's range
  float min_share_in_band = 0.95f;      // share of a cluster's points in the band to be noise

  void validate() const;  // throws std::invalid_argument naming the bad option
};

// The band of heights around the table that its depth noise fills at `range` (m), never
// narrower than `floor_band`.
float table_noise_band(const TableNoiseOptions& options, float floor_band, float range);

struct TableNoiseSplit {
  std::vector<std::vector<std::uint32_t>> objects;  // the clusters kept, in their order
  std::vector<std::uint32_t> table_points;          // points of the noise clusters, ascending
};

// `height` holds the signed distance above the table of every point the clusters name; ranges
// are distances from `sensor`. `floor_band` is the table band the noise band never falls below.
TableNoiseSplit separate_table_noise(const std::vector<Vec3f>& points,
                                     const std::vector<float>& height, const Vec3f& sensor,
                                     std::vector<std::vector<std::uint32_t>> clusters,
                                     float floor_band, const TableNoiseOptions& options);

}  // namespace primlabel::tabletop
