#pragma once
// Geometric ground truth for the objects of real table scenes (the mOSD Kinect scenes, whose
// `label` field marks segments, not primitives). The method:
//   1. the table plane by MSAC + least squares on the table segment; the truth frame is the
//      table's (z up, table top at z = 0), as in the synthetic scenes;
//   2. every object segment gets two models: a box (up to 3 mutually orthogonal faces, each an
//      MSAC plane refined by least squares, standing on the table when its faces are level and
//      its lowest points reach the table) and a closed cylinder (axis and radius by MSAC on
//      point + normal pairs, then Gauss-Newton least squares; upright or lying, on the table when
//      its foot reaches it; its side seen over 45 degrees of arc at least). The model with the
//      lower mean MSAC cost wins. The segment is unfitted (not scored, counted) when fewer than
//      min_inlier_share of its points lie within the residual bound of the model, when the
//      inliers' RMS residual exceeds the RMS bound (the sensor's noise RMS at the segment's
//      median depth plus a margin; a wrong model spreads the residuals over the whole band), or
//      when it lies mostly inside another fitted solid (a pot's inner floor);
//   3. the fitted shapes become a synthetic scene (synth::Scene: the table slab and the shapes),
//      and every point within the residual bound of its surface is labeled by the synthetic
//      ground-truth rule itself (synth::ground_truth at the label radius, then the
//      observed-crease rule) at its closest surface point. Other points are unknown (0).
// Its own error is measured by running it on synthetic Kinect scenes (truth_check.hpp).

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/synth/generate.hpp"

namespace primlabel::synth {

// The mOSD `label` field: 1-9 the table's parts, 20 and above the objects' parts.
inline bool is_mosd_table_label(std::uint32_t label) { return label >= 1 && label <= 9; }
inline bool is_mosd_object_label(std::uint32_t label) { return label >= 20; }

enum class FittedKind { kBox, kUprightCylinder, kLyingCylinder, kUnfitted };
std::string_view fitted_kind_name(FittedKind kind);  // "box", "upright-cylinder", ...

struct FittedObject {
  int segment = 0;
  FittedKind kind = FittedKind::kUnfitted;
  // In the truth frame; the local frames are those of synth::BoxShape, CanShape, LyingCanShape.
  Eigen::Isometry3d table_from_local = Eigen::Isometry3d::Identity();
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // box: x, y, z extents; cylinder: radius, length
  bool on_table = false;
  int faces = 0;                        // box faces found
  std::size_t points = 0, inliers = 0;  // of the segment; within the residual bound of the model
  double rms = 0;                       // residual of the inliers (m)
  double bound = 0;                     // median residual bound of the segment's points (m)
  double max_rms = 0;                   // the RMS bound at the segment's median depth (m)
  // Mean truncated cost of each model, min(d², bound²) / bound² over the segment's points
  // (0: every point on the surface, 1: none within the bound); NaN when the model failed.
  double box_cost = NAN, cylinder_cost = NAN;
  double inlier_share() const { return points ? double(inliers) / double(points) : 0.0; }
};

struct ObjectTruthOptions {
  double label_radius = synth::kDefaultLabelRadius;
  // Residual bound at depth z (along the sensor's view axis): base + z2 · z² (m). Kinect depth
  // noise is 1.425e-3 z² (sigma) and a disparity step ~3.2e-3 z² at 1/8 pixel: three sigma,
  // half a step and 2 mm of model error.
  double residual_base = 0.002, residual_z2 = 0.006;
  double min_inlier_share = 0.8;  // below: the segment is unfitted
  // RMS bound at the median depth z: rms_base + rms_z2 · z² (m). The Kinect noise RMS is
  // sqrt(1.425² + 3.2² / 12) · 1e-3 z² (depth sigma and a uniform disparity step), and 1.5 mm
  // allows for print, bulges and rounded edges.
  double rms_base = 0.0015, rms_z2 = 0.0017;
  double contact_tolerance = 0.02;  // lowest points this close to the table: standing on it (m)
  std::size_t min_segment_points = 50;
  float normal_radius = 0.015f;  // PCA normals for the cylinder hypotheses (m)
  std::uint64_t seed = 1;
};

struct ObjectTruth {
  std::vector<std::uint32_t> labels;  // per point, taxonomy ids; 0 = not scored
  Eigen::Isometry3d table_from_cloud = Eigen::Isometry3d::Identity();
  std::vector<FittedObject> objects;  // one per object segment, ascending segment ids
  std::size_t count(FittedKind kind) const;
};

// Per point: -1 ignored (invalid), 0 table, > 0 an object segment id.
std::vector<int> mosd_segments(const std::vector<std::uint32_t>& mosd_labels);  // 1-9 table, 20+
std::vector<int> synthetic_segments(const PointCloud& cloud);  // the `object` field of synth

// Throws std::invalid_argument when segments does not match the cloud or no table plane is found.
// `search`, an index on cloud.xyz, saves building one; objects are fitted in parallel, each with
// its own seed, so the result does not depend on context.threads.
ObjectTruth fit_object_truth(const PointCloud& cloud, const std::vector<int>& segments,
                             const ObjectTruthOptions& options = {}, const RunContext& context = {},
                             const NeighborSearch* search = nullptr);

}  // namespace primlabel::synth
