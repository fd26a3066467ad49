#include "primlabel/tabletop/tabletop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/tabletop/convex_hull.hpp"
#include "primlabel/tabletop/plane_grid.hpp"
#include "primlabel/tabletop/support_surface.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::tabletop {

void TabletopOptions::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (up_source == UpAxisSource::kGiven && (!is_finite(up) || up.norm() < 1e-6f))
    fail("the given up axis must be a finite non-zero vector");
  if (!(max_tilt_deg > 0.0f && max_tilt_deg <= 90.0f))
    fail("max tilt must be in (0, 90] degrees, got " + std::to_string(max_tilt_deg));
  if (!(estimate_prior_angle_deg > 0.0f && estimate_prior_angle_deg <= 90.0f))
    fail("the up prior angle must be in (0, 90] degrees, got " +
         std::to_string(estimate_prior_angle_deg));
  if (!(voxel_leaf >= 0.0f) || !std::isfinite(voxel_leaf))
    fail("voxel leaf must be >= 0, got " + std::to_string(voxel_leaf));
  if (!(table_band > 0.0f) || !std::isfinite(table_band))
    fail("table band must be positive, got " + std::to_string(table_band));
  if (!(table_connectivity > 0.0f) || !std::isfinite(table_connectivity))
    fail("table connectivity must be positive, got " + std::to_string(table_connectivity));
  if (!(table_min_part >= 0.0f && table_min_part <= 1.0f))
    fail("table min part must be in [0, 1], got " + std::to_string(table_min_part));
  if (!(min_table_parallel >= 0.0f && min_table_parallel <= 1.0f))
    fail("min table parallel must be in [0, 1], got " + std::to_string(min_table_parallel));
  if (!(table_normal_angle_deg > 0.0f && table_normal_angle_deg <= 90.0f))
    fail("table normal angle must be in (0, 90] degrees, got " +
         std::to_string(table_normal_angle_deg));
  const float min_height = min_object_height.value_or(-table_band);
  if (!std::isfinite(min_height) || !std::isfinite(max_object_height) ||
      min_height > max_object_height)
    fail("object height range [" + std::to_string(min_height) + ", " +
         std::to_string(max_object_height) + "] is empty");
  if (!std::isfinite(hull_margin)) fail("hull margin must be finite");
  plane.validate();
  clusters.validate();
  support.validate();
  table_noise.validate();
  creases.validate();
  split.validate();
  merge.validate();
}

const char* to_string(TabletopStatus status) {
  switch (status) {
    case TabletopStatus::kOk:
      return "ok";
    case TabletopStatus::kNoValidPoints:
      return "no_valid_points";
    case TabletopStatus::kNoPlane:
      return "no_plane";
    case TabletopStatus::kPlaneNotHorizontal:
      return "plane_not_horizontal";
  }
  return "unknown";
}

namespace {

constexpr const char* kWhat = "table-top segmentation";

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// A camera frame has y pointing down the image, so the sensor's up is -y turned by its pose.
Vec3f sensor_up(const Viewpoint& viewpoint) {
  return (viewpoint.orientation.normalized() * Vec3f(0, -1, 0)).normalized();
}

float angle_between_deg(const Vec3f& a, const Vec3f& b) {
  const float c = std::clamp(a.normalized().dot(b.normalized()), -1.0f, 1.0f);
  return std::acos(c) * 180.0f / static_cast<float>(M_PI);
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

TabletopResult segment_tabletop(const PointCloud& cloud, const TabletopOptions& options,
                                const RunContext& context) {
  options.validate();
  context.throw_if_stopped(kWhat);
  const auto start = Clock::now();
  TabletopResult result;
  const std::vector<Vec3f>& xyz = cloud.xyz;

  // 1. Valid points, optionally reduced to voxel centroids for the plane fit and clustering.
  const std::vector<std::uint32_t> valid = finite_indices(xyz);
  result.valid_points = valid.size();
  if (valid.empty()) {
    result.status = TabletopStatus::kNoValidPoints;
    result.message = cloud.empty() ? "the cloud is empty" : "no point has finite coordinates";
    result.timings.total_ms = ms_since(start);
    return result;
  }
  const bool voxelized = options.voxel_leaf > 0.0f;
  VoxelGrid grid;
  std::vector<std::uint32_t> all_voxels;
  if (voxelized) {
    grid = voxel_downsample(xyz, valid, options.voxel_leaf, context);
    all_voxels.resize(grid.centroids.size());
    std::iota(all_voxels.begin(), all_voxels.end(), 0u);
  }
  const std::vector<Vec3f>& fit_points = voxelized ? grid.centroids : xyz;
  const std::vector<std::uint32_t>& fit_indices = voxelized ? all_voxels : valid;
  result.timings.prepare_ms = ms_since(start);

  // 2. The table plane: the best plane within the allowed angle of the up prior.
  const auto plane_start = Clock::now();
  PlaneFitOptions plane_options = options.plane;
  plane_options.seed = options.seed;
  Vec3f prior = sensor_up(cloud.viewpoint);
  if (options.up_source == UpAxisSource::kGiven) prior = options.up.normalized();
  plane_options.axis = prior;
  plane_options.max_angle_deg = options.up_source == UpAxisSource::kEstimate
                                    ? options.estimate_prior_angle_deg
                                    : options.max_tilt_deg;
  if (voxelized)  // the voxel count, not the point count, is what the fit sees
    plane_options.min_inliers =
        std::max<std::size_t>(3, options.plane.min_inliers * grid.centroids.size() / valid.size());
  const PlaneFit fit = fit_plane(fit_points, fit_indices, plane_options, context);
  result.timings.plane_ms = ms_since(plane_start);
  const auto fail = [&](const PlaneFit& failed) {
    result.status = failed.status == PlaneFitStatus::kNotWithinAngle
                        ? TabletopStatus::kPlaneNotHorizontal
                        : TabletopStatus::kNoPlane;
    result.message = failed.message;
    result.tilt_deg = failed.angle_to_axis_deg;
    result.table_inliers.clear();
    result.timings.total_ms = ms_since(start);
    return result;
  };
  if (fit.status != PlaneFitStatus::kOk) return fail(fit);
  Eigen::Vector4f plane = fit.plane;
  // Estimated up: the table is seen from above, so its normal faces the sensor.
  if (options.up_source == UpAxisSource::kEstimate &&
      signed_distance(plane, cloud.viewpoint.origin) < 0.0f)
    plane = -plane;
  result.plane = plane;
  result.up = plane.head<3>();
  result.tilt_deg = angle_between_deg(plane.head<3>(), prior);

  context.throw_if_stopped(kWhat);
  // 3. The table: the band around the plane, in the pieces connected to its bulk - or, when the
  // dominant plane stands on a lower one that holds up more of the scene, that one.
  const auto table_start = Clock::now();
  const SurfaceRules rules{options.table_band,
                           options.table_connectivity,
                           options.table_min_part,
                           options.min_table_parallel,
                           options.table_normal_angle_deg,
                           3.0f * options.plane.distance_threshold,
                           options.min_object_height.value_or(-options.table_band),
                           options.max_object_height};
  TableSurface surface = table_surface(xyz, valid, plane, rules);
  const char* not_a_table = surface.not_a_table;
  if (not_a_table) {
    // Otherwise there is no table within the allowed angle; say how far off the dominant plane is.
    PlaneFitOptions free = plane_options;
    free.axis.reset();
    PlaneFit dominant = fit_plane(fit_points, fit_indices, free, context);
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
    return fail(failed);
  }
  {
    std::size_t best_support = support_count(xyz, valid, surface, rules, options.support);
    for (const Eigen::Vector4f& candidate :
         further_horizontal_planes(fit_points, fit_indices, plane, fit.inliers, plane_options,
                                   options.support, context)) {
      context.throw_if_stopped(kWhat);
      TableSurface other = table_surface(xyz, valid, candidate, rules);
      const std::size_t support = support_count(xyz, valid, other, rules, options.support);
      if (support > best_support) {
        best_support = support;
        surface = std::move(other);
      }
    }
  }
  plane = surface.plane;
  result.plane = plane;
  result.up = plane.head<3>();
  result.tilt_deg = angle_between_deg(plane.head<3>(), prior);
  const std::vector<float>& height = surface.height;
  const PlaneGrid& band_grid = *surface.band_grid;
  const std::vector<std::uint8_t>& is_table = surface.is_table;
  result.table_inliers = surface.inliers;

  Vec3f u, v;
  plane_basis(plane.head<3>(), u, v);
  const std::vector<Vec2f>& hull = surface.hull;
  const Vec3f on_plane = -plane[3] * plane.head<3>();
  for (const Vec2f& q : hull) result.hull.push_back(on_plane + q.x() * u + q.y() * v);
  result.timings.table_ms = ms_since(table_start);

  context.throw_if_stopped(kWhat);
  // 4. Objects: what stands on the table, inside its boundary, grouped by proximity.
  const auto objects_start = Clock::now();
  const float min_height = rules.min_height;
  // Below the table inside its boundary is only the table seen through depth noise.
  std::vector<std::uint32_t> candidates, below_table;
  for (std::uint32_t i : valid) {
    if (is_table[i] || height[i] > options.max_object_height) continue;
    const bool below = height[i] < min_height;
    if (below && (!options.table_noise.enabled ||
                  -height[i] > table_noise_band(options.table_noise, options.table_band,
                                                (xyz[i] - cloud.viewpoint.origin).norm())))
      continue;
    if (hull_contains(hull, band_grid.project(xyz[i]), options.hull_margin))
      (below ? below_table : candidates).push_back(i);
  }
  // Every cluster, whatever its size: the size limits apply after the table's noise is told apart.
  ClusterOptions unlimited = options.clusters;
  unlimited.min_size = 1;
  unlimited.max_size = SIZE_MAX;
  if (voxelized) {
    // Cluster the voxels holding candidates, at their candidates' centroid.
    VoxelGrid object_grid = voxel_downsample(xyz, candidates, options.voxel_leaf, context);
    std::vector<std::uint32_t> voxels(object_grid.centroids.size());
    std::iota(voxels.begin(), voxels.end(), 0u);
    result.clusters = expand_voxel_clusters(
        euclidean_clusters(object_grid.centroids, voxels, unlimited), object_grid);
  } else {
    result.clusters = euclidean_clusters(xyz, candidates, unlimited);
  }
  {
    TableNoiseSplit noise =
        separate_table_noise(xyz, height, cloud.viewpoint.origin, std::move(result.clusters),
                             options.table_band, options.table_noise);
    // Clusters too small or too large to be objects are dropped only now: small flat patches of
    // the table's noise are table.
    result.clusters.clear();
    for (auto& cluster : noise.objects)
      if (cluster.size() >= options.clusters.min_size &&
          cluster.size() <= options.clusters.max_size)
        result.clusters.push_back(std::move(cluster));
    noise.table_points.insert(noise.table_points.end(), below_table.begin(), below_table.end());
    std::sort(noise.table_points.begin(), noise.table_points.end());
    if (!noise.table_points.empty()) {
      std::vector<std::uint32_t> table;
      std::merge(result.table_inliers.begin(), result.table_inliers.end(),
                 noise.table_points.begin(), noise.table_points.end(), std::back_inserter(table));
      result.table_inliers = std::move(table);
    }
  }
  context.throw_if_stopped(kWhat);
  // 5. Objects as wholes: cut touching objects at their creases and split stacked objects first, so
  // that the lower object's occluded parts can still be joined to what remains of it.
  const auto refine_start = Clock::now();
  result.clusters = split_at_concave_creases(cloud, std::move(result.clusters), options.creases);
  result.clusters = split_stacked(xyz, height, plane, std::move(result.clusters), options.split);
  result.clusters =
      merge_occluded(cloud, height, band_grid, std::move(result.clusters), options.merge);
  context.throw_if_stopped(kWhat);
  result.timings.refine_ms = ms_since(refine_start);
  result.timings.objects_ms = ms_since(objects_start);

  result.status = TabletopStatus::kOk;
  char text[160];
  std::snprintf(text, sizeof text, "table: %zu points, tilt %.1f deg; %zu objects",
                result.table_inliers.size(), result.tilt_deg, result.clusters.size());
  result.message = text;
  result.timings.total_ms = ms_since(start);
  return result;
}

std::vector<std::int32_t> segment_ids(const TabletopResult& result, std::size_t num_points) {
  std::vector<std::int32_t> ids(num_points, -1);
  for (std::uint32_t i : result.table_inliers)
    if (i < num_points) ids[i] = 0;
  for (std::size_t k = 0; k < result.clusters.size(); ++k)
    for (std::uint32_t i : result.clusters[k])
      if (i < num_points) ids[i] = static_cast<std::int32_t>(k + 1);
  return ids;
}

std::vector<std::uint8_t> tabletop_mask(const TabletopResult& result, std::size_t num_points) {
  std::vector<std::uint8_t> mask(num_points, 0);
  const std::vector<std::int32_t> ids = segment_ids(result, num_points);
  for (std::size_t i = 0; i < num_points; ++i) mask[i] = ids[i] >= 0 ? 1 : 0;
  return mask;
}

}  // namespace primlabel::tabletop
