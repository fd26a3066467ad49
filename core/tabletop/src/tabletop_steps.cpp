#include "tabletop_steps.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <numeric>
#include <string>

#include "primlabel/tabletop/convex_hull.hpp"
#include "primlabel/tabletop/plane_grid.hpp"

namespace primlabel::tabletop::steps {

namespace {

// A camera frame has y pointing down the image, so the sensor's up is -y turned by its pose.
Vec3f sensor_up(const Viewpoint& viewpoint) {
  return (viewpoint.orientation.normalized() * Vec3f(0, -1, 0)).normalized();
}

// Expands clusters of voxels into clusters of the voxels' input points.
std::vector<std::vector<std::uint32_t>> expand_voxel_clusters(
    const std::vector<std::vector<std::uint32_t>>& voxel_clusters, const VoxelGrid& grid) {
  std::vector<std::vector<std::uint32_t>> clusters;
  for (const auto& voxels : voxel_clusters) {
    std::vector<std::uint32_t> members;
    for (std::uint32_t v : voxels)
      members.insert(members.end(), grid.members.begin() + grid.member_offsets[v],
                     grid.members.begin() + grid.member_offsets[v + 1]);
    std::sort(members.begin(), members.end());
    clusters.push_back(std::move(members));
  }
  std::sort(clusters.begin(), clusters.end(), [](const auto& a, const auto& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  return clusters;
}

}  // namespace

FitPoints fit_points(const std::vector<Vec3f>& xyz, const TabletopOptions& options,
                     const RunContext& context) {
  FitPoints fit;
  fit.valid = finite_indices(xyz);
  fit.voxelized = options.voxel_leaf > 0.0f && !fit.valid.empty();
  if (fit.voxelized) {
    fit.grid = voxel_downsample(xyz, fit.valid, options.voxel_leaf, context);
    fit.all_voxels.resize(fit.grid.centroids.size());
    std::iota(fit.all_voxels.begin(), fit.all_voxels.end(), 0u);
  }
  return fit;
}

Vec3f up_prior(const Viewpoint& viewpoint, const TabletopOptions& options) {
  if (options.up_source == UpAxisSource::kGiven) return options.up.normalized();
  return sensor_up(viewpoint);
}

float angle_between_deg(const Vec3f& a, const Vec3f& b) {
  const float c = std::clamp(a.normalized().dot(b.normalized()), -1.0f, 1.0f);
  return std::acos(c) * 180.0f / static_cast<float>(M_PI);
}

PlaneFitOptions table_plane_options(const TabletopOptions& options, const Vec3f& prior,
                                    const FitPoints& fit) {
  PlaneFitOptions plane_options = options.plane;
  plane_options.seed = options.seed;
  plane_options.axis = prior;
  plane_options.max_angle_deg = options.up_source == UpAxisSource::kEstimate
                                    ? options.estimate_prior_angle_deg
                                    : options.max_tilt_deg;
  if (fit.voxelized)  // the voxel count, not the point count, is what the fit sees
    plane_options.min_inliers = std::max<std::size_t>(
        3, options.plane.min_inliers * fit.grid.centroids.size() / fit.valid.size());
  return plane_options;
}

Eigen::Vector4f facing_up(const Eigen::Vector4f& plane, const TabletopOptions& options,
                          const Viewpoint& viewpoint) {
  if (options.up_source == UpAxisSource::kEstimate &&
      signed_distance(plane, viewpoint.origin) < 0.0f)
    return -plane;
  return plane;
}

SurfaceRules surface_rules(const TabletopOptions& options) {
  return {options.table_band,
          options.table_connectivity,
          options.table_min_part,
          options.min_table_parallel,
          options.table_normal_angle_deg,
          3.0f * options.plane.distance_threshold,
          options.min_object_height.value_or(-options.table_band),
          options.max_object_height};
}

PlaneFit no_table_within_angle(const char* not_a_table, const std::vector<Vec3f>& xyz,
                               const FitPoints& fit, const PlaneFitOptions& plane_options,
                               const Vec3f& prior, const RunContext& context) {
  PlaneFitOptions free = plane_options;
  free.axis.reset();
  const PlaneFit dominant = fit_plane(fit.points(xyz), fit.indices(), free, context);
  PlaneFit failed;
  failed.status = PlaneFitStatus::kNoPlane;
  failed.message = "the best plane within " + std::to_string(int(plane_options.max_angle_deg)) +
                   " deg of up is " + not_a_table + ", not a table";
  if (dominant.status == PlaneFitStatus::kOk) {
    failed.status = PlaneFitStatus::kNotWithinAngle;
    failed.angle_to_axis_deg = angle_between_deg(dominant.plane.head<3>(), prior);
    failed.angle_to_axis_deg =
        std::min(failed.angle_to_axis_deg, 180.0f - failed.angle_to_axis_deg);
    char text[300];
    std::snprintf(text, sizeof text,
                  "no table within %.1f deg of the up axis (the best plane there is %s); the "
                  "dominant plane (%zu points) is %.1f deg off",
                  plane_options.max_angle_deg, not_a_table, dominant.inliers.size(),
                  failed.angle_to_axis_deg);
    failed.message = text;
  }
  return failed;
}

TableSurface supporting_surface(TableSurface surface, const std::vector<Vec3f>& xyz,
                                const FitPoints& fit, const PlaneFit& dominant,
                                const PlaneFitOptions& plane_options, const SurfaceRules& rules,
                                const TabletopOptions& options, const RunContext& context) {
  std::size_t best_support = support_count(xyz, fit.valid, surface, rules, options.support);
  for (const Eigen::Vector4f& candidate :
       further_horizontal_planes(fit.points(xyz), fit.indices(), surface.plane, dominant.inliers,
                                 plane_options, options.support, context)) {
    context.throw_if_stopped(kWhat);
    TableSurface other = table_surface(xyz, fit.valid, candidate, rules);
    const std::size_t support = support_count(xyz, fit.valid, other, rules, options.support);
    if (support > best_support) {
      best_support = support;
      surface = std::move(other);
    }
  }
  return surface;
}

void describe_table(const TableSurface& surface, const Vec3f& prior, TabletopResult& result) {
  const Eigen::Vector4f& plane = surface.plane;
  result.plane = plane;
  result.up = plane.head<3>();
  result.tilt_deg = angle_between_deg(plane.head<3>(), prior);
  result.table_inliers = surface.inliers;
  Vec3f u, v;
  plane_basis(plane.head<3>(), u, v);
  const Vec3f on_plane = -plane[3] * plane.head<3>();
  for (const Vec2f& q : surface.hull) result.hull.push_back(on_plane + q.x() * u + q.y() * v);
}

ObjectCandidates object_candidates(const PointCloud& cloud, const std::vector<std::uint32_t>& valid,
                                   const TableSurface& surface, const SurfaceRules& rules,
                                   const TabletopOptions& options) {
  const std::vector<Vec3f>& xyz = cloud.xyz;
  const std::vector<float>& height = surface.height;
  ObjectCandidates candidates;
  HullMembership inside_hull(surface.hull, options.hull_margin, surface.band_grid->cell());
  for (std::uint32_t i : valid) {
    if (surface.is_table[i] || height[i] > options.max_object_height) continue;
    // Below the table inside its boundary is only the table seen through depth noise.
    const bool below = height[i] < rules.min_height;
    if (below && (!options.table_noise.enabled ||
                  -height[i] > table_noise_band(options.table_noise, options.table_band,
                                                (xyz[i] - cloud.viewpoint.origin).norm())))
      continue;
    if (inside_hull.contains(surface.band_grid->project(xyz[i])))
      (below ? candidates.below_table : candidates.above).push_back(i);
  }
  return candidates;
}

std::vector<std::vector<std::uint32_t>> cluster_candidates(
    const std::vector<Vec3f>& xyz, const std::vector<std::uint32_t>& candidates,
    const TabletopOptions& options, const RunContext& context) {
  // Every cluster, whatever its size: the size limits apply after the table's noise is told apart.
  ClusterOptions unlimited = options.clusters;
  unlimited.min_size = 1;
  unlimited.max_size = SIZE_MAX;
  if (!(options.voxel_leaf > 0.0f)) return euclidean_clusters(xyz, candidates, unlimited);
  // Cluster the voxels holding candidates, at their candidates' centroid.
  const VoxelGrid object_grid = voxel_downsample(xyz, candidates, options.voxel_leaf, context);
  std::vector<std::uint32_t> voxels(object_grid.centroids.size());
  std::iota(voxels.begin(), voxels.end(), 0u);
  return expand_voxel_clusters(euclidean_clusters(object_grid.centroids, voxels, unlimited),
                               object_grid);
}

void separate_table_noise_from_objects(const PointCloud& cloud, const TableSurface& surface,
                                       std::vector<std::vector<std::uint32_t>> clusters,
                                       const std::vector<std::uint32_t>& below_table,
                                       const TabletopOptions& options, TabletopResult& result) {
  TableNoiseSplit noise =
      separate_table_noise(cloud.xyz, surface.height, cloud.viewpoint.origin, std::move(clusters),
                           options.table_band, options.table_noise);
  // Small flat patches of the table's noise are table, so the size limits apply only now.
  result.clusters.clear();
  for (auto& cluster : noise.objects)
    if (cluster.size() >= options.clusters.min_size && cluster.size() <= options.clusters.max_size)
      result.clusters.push_back(std::move(cluster));
  noise.table_points.insert(noise.table_points.end(), below_table.begin(), below_table.end());
  std::sort(noise.table_points.begin(), noise.table_points.end());
  if (!noise.table_points.empty()) {
    std::vector<std::uint32_t> table;
    std::merge(result.table_inliers.begin(), result.table_inliers.end(), noise.table_points.begin(),
               noise.table_points.end(), std::back_inserter(table));
    result.table_inliers = std::move(table);
  }
}

std::vector<std::vector<std::uint32_t>> refine_objects(
    const PointCloud& cloud, const TableSurface& surface,
    std::vector<std::vector<std::uint32_t>> clusters, const TabletopOptions& options,
    const RunContext& context) {
  clusters = split_at_concave_creases(cloud, std::move(clusters), options.creases);
  KeptApart other_objects;
  clusters = split_by_shape(cloud, surface.height, surface.plane.head<3>(), std::move(clusters),
                            options.shapes, &other_objects, context);
  clusters =
      split_stacked(cloud.xyz, surface.height, surface.plane, std::move(clusters), options.split);
  return merge_occluded(cloud, surface.height, *surface.band_grid, std::move(clusters),
                        options.merge, other_objects);
}

}  // namespace primlabel::tabletop::steps
