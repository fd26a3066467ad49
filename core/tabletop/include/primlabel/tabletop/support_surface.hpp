#pragma once
// The table: the horizontal surface that holds the scene up. The largest horizontal plane is not
// always the table: a tray, a stack of books or a wide box top can fill more of the image than the
// table seen around them, and a floor can be wider than the table. Every horizontal surface holds
// up itself and whatever stands on it (points inside its boundary, at most an object's height
// above it); the table holds the most, since whatever stands on a tray stands on the table too,
// and the table stands higher above the floor than any object.
//
// Candidates: the dominant horizontal plane, then the dominant plane among the points off it
// (parallel to it), and so on; only planes holding a fair share of the first one's points are
// considered, so a scene with one table pays one extra plane fit. A candidate must be a table
// surface (see TableSurface) to be chosen.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/tabletop/plane_fit.hpp"
#include "primlabel/tabletop/plane_grid.hpp"

namespace primlabel::tabletop {

struct SupportOptions {
  bool enabled = true;                // false: the dominant horizontal plane is the table
  int max_candidates = 4;             // horizontal planes compared, the dominant one included
  float parallel_deg = 10.0f;         // further candidates lie within this of the dominant plane
  float min_point_share = 0.1f;       // and hold at least this share of its inliers
  std::size_t scoring_points = 5000;  // RANSAC scoring subset for the further candidates
  int count_stride = 4;               // support counted on every count_stride-th point

  void validate() const;  // throws std::invalid_argument naming the bad option
};

// What makes a plane a table, and what stands on it (TabletopOptions' fields).
struct SurfaceRules {
  float band;                    // table points: |height| <= band (m)
  float connectivity;            // band cells joined within this (m)
  float min_part;                // pieces of the band at least this share of the largest are table
  float min_parallel;            // share of the largest piece whose local surface is parallel
  float normal_angle_deg;        // ... within this angle
  float min_narrow_spread;       // the largest piece is at least this wide (m, std. deviation)
  float min_height, max_height;  // objects stand between these heights (m)
};

// A plane's table: the band around it, its pieces connected to the bulk, and their boundary.
struct TableSurface {
  Eigen::Vector4f plane = Eigen::Vector4f::Zero();
  std::vector<float> height;             // signed distance of every point; NaN where invalid
  std::vector<std::uint32_t> band;       // points with |height| <= band, ascending
  std::unique_ptr<PlaneGrid> band_grid;  // the band binned in the plane
  const char* not_a_table = nullptr;     // why the band is no table surface; null when it is one
  std::vector<std::uint8_t> is_table;    // per point
  std::vector<std::uint32_t> inliers;    // the table's points, ascending
  std::vector<Vec2f> hull;               // its convex hull in the band grid's plane coordinates
};

// The table surface of `plane` among points[valid].
TableSurface table_surface(const std::vector<Vec3f>& points,
                           const std::vector<std::uint32_t>& valid, const Eigen::Vector4f& plane,
                           const SurfaceRules& rules);

// Points (counted on every options.count_stride-th valid point) that `surface` holds up: its own
// and those standing on it inside its boundary.
std::size_t support_count(const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& valid,
                          const TableSurface& surface, const SurfaceRules& rules,
                          const SupportOptions& options);

// Further horizontal planes among points[indices] off the dominant plane (its inliers, ascending,
// excluded), each parallel to it within options.parallel_deg and oriented like it; largest first.
std::vector<Eigen::Vector4f> further_horizontal_planes(
    const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& indices,
    const Eigen::Vector4f& dominant, const std::vector<std::uint32_t>& inliers,
    const PlaneFitOptions& fit_options, const SupportOptions& options, const RunContext& context);

}  // namespace primlabel::tabletop
