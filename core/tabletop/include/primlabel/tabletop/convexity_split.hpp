#pragma once
// Splits a cluster where touching objects meet at a concave crease (a box against a box, a can
// against a box, a box lying on a book), in the spirit of LCCP (Stein et al. 2014, "Object
// Partitioning using Local Convexity"): the cluster is cut into voxel patches, each with a
// centroid and a surface normal (from the patch and its 6 face neighbours, facing the
// sensor); face-neighbouring patches are joined only where their connection is convex. With d the
// unit vector from patch j's centroid to patch i's, the connection is convex when n_i.d > n_j.d
// (the surfaces bend away from each other), or smooth when the normals differ by less than
// concavity_tolerance_deg (noise, gentle curvature). LCCP's sanity criterion rejects convex-looking
// steps: when d is nearly parallel to n_i x n_j the patches are side by side, not around a fold.
//
// Segments too small to be an object (noisy patches at boundaries, mixed pixels) are not cut:
// segments are joined, smallest first, to the neighbour they share most patch connections with
// until every segment holds min_segment_points, so a split needs two object-sized sides. A cut
// then stands only at a crease: most connections across it are concave folds, and the fold is
// sharp or the two sides differ in colour. The inside of a bowl meets its floor and its outer
// wall in gentle folds of one material, so it stays whole.
// Deterministic: patches are ordered by their integer coordinates, joins by size then index.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::tabletop {

struct ConvexitySplitOptions {
  bool enabled = true;
  float patch_size = 0.01f;  // voxel patch edge (m): several Kinect pixels at 1 m, above noise
  float concavity_tolerance_deg = 10.0f;  // concave folds flatter than this are smooth
  bool sanity_check = true;               // reject step-like "convex" connections
  std::size_t min_segment_points = 400;   // both sides of a cut hold at least this many points
  // A cut stands where most of the boundary's connections are concave folds (min_fold_share)
  // and the fold is sharp (mean angle between the normals across it) or the colours differ.
  float min_fold_share = 0.5f;
  float sharp_fold_deg = 30.0f;
  float min_chromaticity_difference = 0.05f;

  void validate() const;  // throws std::invalid_argument naming the bad option
};

// Organised clouds only (one view, so normals can face the sensor); others are returned whole.
// Returns the clusters with each cut at its concave creases: input indices ascending within each
// piece, pieces ordered by size (largest first, ties by first index). `viewpoint` orients the
// normals (the cloud's VIEWPOINT origin is the sensor); its colour, when it has one, tells
// materials.
std::vector<std::vector<std::uint32_t>> split_at_concave_creases(
    const PointCloud& cloud, std::vector<std::vector<std::uint32_t>> clusters,
    const ConvexitySplitOptions& options);

}  // namespace primlabel::tabletop
