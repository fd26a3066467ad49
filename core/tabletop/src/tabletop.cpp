#include "primlabel/tabletop/tabletop.hpp"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <utility>

#include "primlabel/geometry/cancellation.hpp"
#include "tabletop_steps.hpp"

namespace primlabel::tabletop {

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

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// A result that says why there is no table (the fit's status and message).
TabletopResult no_table(TabletopResult result, const PlaneFit& failed, Clock::time_point start) {
  result.status = failed.status == PlaneFitStatus::kNotWithinAngle
                      ? TabletopStatus::kPlaneNotHorizontal
                      : TabletopStatus::kNoPlane;
  result.message = failed.message;
  result.tilt_deg = failed.angle_to_axis_deg;
  result.table_inliers.clear();
  result.timings.total_ms = ms_since(start);
  return result;
}

}  // namespace

// The recipe; each step is in tabletop_steps.cpp.
TabletopResult segment_tabletop(const PointCloud& cloud, const TabletopOptions& options,
                                const RunContext& context) {
  using namespace steps;
  options.validate();
  context.throw_if_stopped(kWhat);
  const auto start = Clock::now();
  TabletopResult result;
  const std::vector<Vec3f>& xyz = cloud.xyz;

  // 1. Valid points, optionally reduced to voxel centroids for the plane fit and clustering.
  const FitPoints fit = fit_points(xyz, options, context);
  result.valid_points = fit.valid.size();
  if (fit.valid.empty()) {
    result.status = TabletopStatus::kNoValidPoints;
    result.message = cloud.empty() ? "the cloud is empty" : "no point has finite coordinates";
    result.timings.total_ms = ms_since(start);
    return result;
  }
  result.timings.prepare_ms = ms_since(start);

  // 2. The table plane: the best plane within the allowed angle of the up prior.
  const auto plane_start = Clock::now();
  const Vec3f prior = up_prior(cloud.viewpoint, options);
  const PlaneFitOptions plane_options = table_plane_options(options, prior, fit);
  const PlaneFit dominant = fit_plane(fit.points(xyz), fit.indices(), plane_options, context);
  result.timings.plane_ms = ms_since(plane_start);
  if (dominant.status != PlaneFitStatus::kOk) return no_table(std::move(result), dominant, start);
  const Eigen::Vector4f plane = facing_up(dominant.plane, options, cloud.viewpoint);
  result.plane = plane;
  result.up = plane.head<3>();
  result.tilt_deg = angle_between_deg(plane.head<3>(), prior);

  context.throw_if_stopped(kWhat);
  // 3. The table: the band around the plane, in the pieces connected to its bulk - or, when the
  // dominant plane stands on a lower one that holds up more of the scene, that one.
  const auto table_start = Clock::now();
  const SurfaceRules rules = surface_rules(options);
  TableSurface surface = table_surface(xyz, fit.valid, plane, rules);
  if (surface.not_a_table)
    return no_table(
        std::move(result),
        no_table_within_angle(surface.not_a_table, xyz, fit, plane_options, prior, context), start);
  surface = supporting_surface(std::move(surface), xyz, fit, dominant, plane_options, rules,
                               options, context);
  describe_table(surface, prior, result);
  result.timings.table_ms = ms_since(table_start);

  context.throw_if_stopped(kWhat);
  // 4. Objects: what stands on the table, inside its boundary, grouped by proximity.
  const auto objects_start = Clock::now();
  const ObjectCandidates candidates = object_candidates(cloud, fit.valid, surface, rules, options);
  separate_table_noise_from_objects(cloud, surface,
                                    cluster_candidates(xyz, candidates.above, options, context),
                                    candidates.below_table, options, result);
  context.throw_if_stopped(kWhat);
  // 5. Objects as wholes: split and joined.
  const auto refine_start = Clock::now();
  result.clusters = refine_objects(cloud, surface, std::move(result.clusters), options, context);
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
