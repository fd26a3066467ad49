#pragma once
// The table-top pre-filter of Rusu et al. (2009): a horizontal plane is the table - the dominant
// one, unless it stands on one that holds up more of the scene (support_surface.hpp); its convex
// hull bounds the table; the points above the table inside the hull, grouped by Euclidean
// clustering, are the objects. Only the table and the objects are then labeled.
//
// Euclidean clusters are then refined (convexity_split.hpp, stacked_split.hpp,
// occlusion_merge.hpp): touching objects are cut apart at the concave creases where they meet,
// objects standing on objects are split at the supporting surface, and parts of one object cut
// apart by occlusion (a nearer object in front of it, or a container's own wall hiding its missing
// rim) are joined.
//
// Data conditions (no valid point, no plane, plane not horizontal) give a TabletopResult with a
// status and a message; only invalid options throw (std::invalid_argument).

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/tabletop/convexity_split.hpp"
#include "primlabel/tabletop/euclidean_clusters.hpp"
#include "primlabel/tabletop/occlusion_merge.hpp"
#include "primlabel/tabletop/plane_fit.hpp"
#include "primlabel/tabletop/shape_split.hpp"
#include "primlabel/tabletop/stacked_split.hpp"
#include "primlabel/tabletop/support_surface.hpp"
#include "primlabel/tabletop/table_noise.hpp"

namespace primlabel::tabletop {

// Where "up" comes from.
enum class UpAxisSource {
  kGiven,     // TabletopOptions::up, in the cloud's frame
  kSensor,    // the sensor's up (-y of a camera frame, rotated by the cloud's VIEWPOINT)
  kEstimate,  // the largest plane within estimate_prior_angle_deg of the sensor's up; its normal
              // (facing the sensor) becomes "up". For tilted cameras with an unknown pose.
};

struct TabletopOptions {
  UpAxisSource up_source = UpAxisSource::kEstimate;
  Vec3f up = Vec3f(0, 0, 1);               // for kGiven
  float max_tilt_deg = 15.0f;              // table normal within this of up (kGiven, kSensor)
  float estimate_prior_angle_deg = 60.0f;  // kEstimate: the cone around the sensor's up

  float voxel_leaf = 0.0f;  // > 0: fit and cluster on voxel centroids (m); 0 = every point

  PlaneFitOptions plane;      // distance_threshold is the fit band; axis is set from up
  float table_band = 0.006f;  // final table membership: |height| <= this (m)
  // The table = the band's points connected through cells of this edge (m) in the table plane
  // (8-neighbours, so gaps narrower than one cell are bridged), in pieces at least
  // table_min_part of the largest.
  float table_connectivity = 0.01f;
  float table_min_part = 0.1f;
  // A table is a surface lying in the plane, not a plane slicing through other surfaces: at
  // least this fraction of its points must have a local surface (3x3 cells) within
  // table_normal_angle_deg of the plane.
  float min_table_parallel = 0.5f;
  float table_normal_angle_deg = 20.0f;

  // Object candidates: not table, projected inside the hull, height above the plane in
  // [min_object_height, max_object_height]. Unset minimum = -table_band, so points in the table's
  // band that are not connected to the table (the floor of a bowl) may belong to objects.
  std::optional<float> min_object_height;
  float max_object_height = 0.5f;
  float hull_margin = 0.0f;  // grow (> 0) or shrink (< 0) the table hull (m)
  ClusterOptions clusters{0.02f, 100, 200000};
  SupportOptions support;         // the table among several horizontal surfaces
  TableNoiseOptions table_noise;  // flat clusters within the depth noise of the table: table
  ConvexitySplitOptions creases;  // touching objects, cut at concave creases
  ShapeSplitOptions shapes;       // touching objects, cut where their fitted shapes meet
  StackSplitOptions split;        // objects standing on objects
  OcclusionMergeOptions merge;    // parts of one object cut apart by occlusion (organised clouds)

  std::uint64_t seed = 1;  // RANSAC seed (copied into plane.seed)

  void validate() const;  // throws std::invalid_argument naming the bad option
};

enum class TabletopStatus {
  kOk,
  kNoValidPoints,       // empty cloud, or no point with finite coordinates
  kNoPlane,             // no plane with enough support
  kPlaneNotHorizontal,  // the dominant plane is not within the allowed angle of up
};

const char* to_string(TabletopStatus status);

struct TabletopTimings {
  double total_ms = 0, prepare_ms = 0, plane_ms = 0, table_ms = 0, objects_ms = 0;
  double refine_ms = 0;  // split and merge (part of objects_ms)
};

struct TabletopResult {
  TabletopStatus status = TabletopStatus::kNoValidPoints;
  std::string message;  // one line; says why when status != kOk

  Eigen::Vector4f plane = Eigen::Vector4f::Zero();   // n.p + d = 0, n = up side of the table
  Vec3f up = Vec3f::Zero();                          // the up axis used (unit)
  float tilt_deg = 0.0f;                             // angle between plane normal and prior up
  std::vector<std::uint32_t> table_inliers;          // input indices, ascending
  std::vector<Vec3f> hull;                           // table boundary on the plane, CCW about n
  std::vector<std::vector<std::uint32_t>> clusters;  // objects: input indices, largest first
  std::size_t valid_points = 0;
  TabletopTimings timings;

  bool ok() const { return status == TabletopStatus::kOk; }
};

// context.stop is checked between the stages, per round of the plane fit and inside the voxel
// filter (segment_tabletop then throws Cancelled); results do not depend on context.threads.
TabletopResult segment_tabletop(const PointCloud& cloud, const TabletopOptions& options,
                                const RunContext& context = {});

// Per-point segment: -1 neither table nor object, 0 table, k + 1 for clusters[k].
std::vector<std::int32_t> segment_ids(const TabletopResult& result, std::size_t num_points);

// Per-point selection for "label the table and the objects only": 1 on table and object points.
std::vector<std::uint8_t> tabletop_mask(const TabletopResult& result, std::size_t num_points);

}  // namespace primlabel::tabletop
