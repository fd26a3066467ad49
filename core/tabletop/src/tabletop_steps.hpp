#pragma once
// The steps of segment_tabletop (tabletop.cpp), each named for what it finds: the points the fit
// sees, the table's plane, the table around it, the objects on it and their refinement.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/tabletop/plane_fit.hpp"
#include "primlabel/tabletop/support_surface.hpp"
#include "primlabel/tabletop/tabletop.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::tabletop::steps {

inline constexpr const char* kWhat = "table-top segmentation";

// The points the plane fit and the clustering see: the valid points, or their voxel centroids.
struct FitPoints {
  std::vector<std::uint32_t> valid;  // input points with finite coordinates, ascending
  bool voxelized = false;
  VoxelGrid grid;                         // voxelized: the valid points' voxels
  std::vector<std::uint32_t> all_voxels;  // voxelized: 0 .. voxel count - 1

  const std::vector<Vec3f>& points(const std::vector<Vec3f>& xyz) const {
    return voxelized ? grid.centroids : xyz;
  }
  const std::vector<std::uint32_t>& indices() const { return voxelized ? all_voxels : valid; }
};

FitPoints fit_points(const std::vector<Vec3f>& xyz, const TabletopOptions& options,
                     const RunContext& context);

// Where up is believed to be before the table is found.
Vec3f up_prior(const Viewpoint& viewpoint, const TabletopOptions& options);

float angle_between_deg(const Vec3f& a, const Vec3f& b);

// The plane fit's options: within the allowed angle of `prior`, its support scaled to voxels.
PlaneFitOptions table_plane_options(const TabletopOptions& options, const Vec3f& prior,
                                    const FitPoints& fit);

// The fitted plane's normal made to face the sensor when up is estimated (a table is seen from
// above).
Eigen::Vector4f facing_up(const Eigen::Vector4f& plane, const TabletopOptions& options,
                          const Viewpoint& viewpoint);

SurfaceRules surface_rules(const TabletopOptions& options);

// Why there is no table: the plane within the allowed angle is `not_a_table`; the message says
// how far off the dominant plane is.
PlaneFit no_table_within_angle(const char* not_a_table, const std::vector<Vec3f>& xyz,
                               const FitPoints& fit, const PlaneFitOptions& plane_options,
                               const Vec3f& prior, const RunContext& context);

// The table: `surface` (the dominant plane's), unless a further horizontal plane holds up more
// of the scene.
TableSurface supporting_surface(TableSurface surface, const std::vector<Vec3f>& xyz,
                                const FitPoints& fit, const PlaneFit& dominant,
                                const PlaneFitOptions& plane_options, const SurfaceRules& rules,
                                const TabletopOptions& options, const RunContext& context);

// The result's plane, up, tilt, table points and boundary from the chosen surface.
void describe_table(const TableSurface& surface, const Vec3f& prior, TabletopResult& result);

// Points that may belong to objects: not table, above it (within the height range) and inside
// its boundary; and the points inside it below the table that its depth noise explains.
struct ObjectCandidates {
  std::vector<std::uint32_t> above, below_table;
};
ObjectCandidates object_candidates(const PointCloud& cloud, const std::vector<std::uint32_t>& valid,
                                   const TableSurface& surface, const SurfaceRules& rules,
                                   const TabletopOptions& options);

// The candidates grouped by proximity, whatever the group's size (on voxels when voxelized).
std::vector<std::vector<std::uint32_t>> cluster_candidates(
    const std::vector<Vec3f>& xyz, const std::vector<std::uint32_t>& candidates,
    const TabletopOptions& options, const RunContext& context);

// Clusters within the table's depth noise, and the candidates below the table, join the table;
// clusters too small or too large to be objects are dropped only then.
void separate_table_noise_from_objects(const PointCloud& cloud, const TableSurface& surface,
                                       std::vector<std::vector<std::uint32_t>> clusters,
                                       const std::vector<std::uint32_t>& below_table,
                                       const TabletopOptions& options, TabletopResult& result);

// Objects as wholes: touching objects cut at their creases and stacked objects split first, so
// that the lower object's occluded parts can still be joined to what remains of it.
std::vector<std::vector<std::uint32_t>> refine_objects(
    const PointCloud& cloud, const TableSurface& surface,
    std::vector<std::vector<std::uint32_t>> clusters, const TabletopOptions& options,
    const RunContext& context);

}  // namespace primlabel::tabletop::steps
