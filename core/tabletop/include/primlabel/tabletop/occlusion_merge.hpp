#pragma once
// Joins clusters that are parts of one object, cut apart only because the surface between them
// is hidden from the sensor (organised clouds: the image tells what hides what):
//   - an object seen left and right of a nearer object standing in front of it or lying on it;
//   - the outer wall and the inside of a container whose rim the sensor missed (the outer wall
//     itself hides the inner wall's connection to it).
//
// Evidence, along image rows and columns: a pixel of cluster A, then only pixels that are
// invalid or nearer to the sensor than the line between the two ends (an occluder), then a pixel
// of cluster B. Free space seen between them (e.g. the table behind a gap) breaks the chain. With
// no valid pixel between them, A itself may hide B's continuation (a container's outer wall in
// front of its inside) - but that is also how any object in front of another looks, so such
// links need the same material too: mean chromaticities within max_chromaticity_difference
// (when the cloud has colour). A pair needs min_scanlines linking lines.
//
// A linked pair is then joined only when the result is a plausible single object:
//   - the parts reach the same top height (surfaces of one object cut by an occluder, or the
//     inner and outer wall up to one rim; stacked or neighbouring objects seldom agree);
//   - their 3D gap is at most max_gap (what an occlusion may hide within one object);
//   - no table is seen inside their joint footprint in the table plane, away from both parts
//     (two objects with the table visible between them are two objects; table close to a part
//     may be under it: an overhanging rim, a base hidden behind a curved wall).
// Pairs are joined greedily, the best supported first, and every join is checked on the groups
// joined so far. Heights are distances above the table plane; ranges are distances from the
// cloud's VIEWPOINT origin.
//
// Limitation: two objects of one height and material, one right behind the other with the
// table between them hidden, look exactly like one object, and are joined.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/tabletop/kept_apart.hpp"
#include "primlabel/tabletop/plane_grid.hpp"

namespace primlabel::tabletop {

struct OcclusionMergeOptions {
  bool enabled = true;
  float depth_margin = 0.01f;        // an occluder is nearer by at least this (m): above noise
  int max_scan_pixels = 200;         // longest stretch of image followed across an occluder
  int min_scanlines = 5;             // image rows + columns that must link a pair
  float top_tolerance = 0.015f;      // parts of one object: top heights within this (m)
  float max_gap = 0.25f;             // largest 3D gap between the parts (m): object-sized
  float footprint_margin = 0.02f;    // table within this of a part counts as under it (m)
  float max_table_fraction = 0.02f;  // free table points in the footprint, per point of the parts
  float max_chromaticity_difference = 0.05f;  // links without an occluder: one material

  void validate() const;  // throws std::invalid_argument naming the bad option
};

// Returns the clusters with occlusion-split parts joined: input indices ascending within each,
// ordered by size (largest first, ties by first index). Unorganised clouds are returned as they
// are. `height` holds the signed distance above the table of every point the clusters name;
// `table` bins the points of the table's band (the table and what touches it) in the table plane.
// Clusters holding points `kept_apart` says are other objects are never joined, nor a cluster
// holding a ball's or can's solid (KeptApart::solids) and one lying outside it.
std::vector<std::vector<std::uint32_t>> merge_occluded(
    const PointCloud& cloud, const std::vector<float>& height, const PlaneGrid& table,
    std::vector<std::vector<std::uint32_t>> clusters, const OcclusionMergeOptions& options,
    const KeptApart& kept_apart = {});

}  // namespace primlabel::tabletop
