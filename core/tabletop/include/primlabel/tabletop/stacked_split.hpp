#pragma once
// Splits a cluster where one object stands on another (a can on a tin, a box on a box) and they
// touch, so that Euclidean clustering joined them.
//
// The cue is the supporting surface: the top of the lower object is a horizontal surface at a
// height h well above the table, so seen from above it concentrates many of the cluster's points
// in a thin band of heights (a peak of the height histogram; walls spread evenly over heights).
// The cluster is split at h when what rises above the band (1) is a real object (enough points,
// rising clearly above h), (2) stands on the surface (its footprint in the table plane lies over
// the surface's) and (3) leaves the surface seen free outside its own footprint: most of the
// band's points lie outside the upper object's footprint, since the part under it is hidden. So
// a box on a box of nearly the same size splits at the strip of the lower top seen beside it.
// (3) keeps one object whole when its horizontal band is its floor: a container's walls rise
// around its floor, which lies inside their footprint; a box's top face has nothing on it. A
// bottle's shoulder is sloped, so it does not concentrate points in one thin band.
//
// Heights are distances above the table plane. Splits repeat on the parts (three stacked objects
// give three clusters).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::tabletop {

struct StackSplitOptions {
  bool enabled = true;
  float bin = 0.005f;                // height histogram bin (m): about the sensor's depth noise
  float min_support_height = 0.02f;  // a supporting surface lies at least this high (m): lower
                                     // horizontal bands are floors of containers or plinths
  float peak_factor = 5.0f;          // a surface's bins hold >= this times the median bin
  float min_rise = 0.02f;            // the upper object rises at least this above the surface (m)
  std::size_t min_points = 100;      // and has at least this many points
  float min_free_share = 0.5f;       // of the surface's points outside the upper footprint
  float min_on_surface = 0.9f;       // fraction of the upper points above the surface's footprint
  float footprint_margin = 0.01f;    // (m) of slack for that test

  void validate() const;  // throws std::invalid_argument naming the bad option
};

// Returns the clusters with every stacked cluster split into its objects: input indices
// ascending within each, ordered by size (largest first, ties by first index). `height` holds
// the signed distance above the table of every point the clusters name; `plane` is the table.
std::vector<std::vector<std::uint32_t>> split_stacked(
    const std::vector<Vec3f>& points, const std::vector<float>& height,
    const Eigen::Vector4f& plane, std::vector<std::vector<std::uint32_t>> clusters,
    const StackSplitOptions& options);

}  // namespace primlabel::tabletop
