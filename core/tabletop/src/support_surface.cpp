#include "primlabel/tabletop/support_surface.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>

#include "primlabel/tabletop/convex_hull.hpp"

namespace primlabel::tabletop {

void SupportOptions::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (max_candidates < 1 || max_candidates > 16)
    fail("support max candidates must be in [1, 16], got " + std::to_string(max_candidates));
  if (!(parallel_deg > 0.0f && parallel_deg <= 90.0f))
    fail("support parallel angle must be in (0, 90] degrees");
  if (!(min_point_share > 0.0f && min_point_share <= 1.0f))
    fail("support min point share must be in (0, 1]");
  if (scoring_points < 3) fail("support scoring points must be at least 3");
  if (count_stride < 1) fail("support count stride must be at least 1");
}

TableSurface table_surface(const std::vector<Vec3f>& points,
                           const std::vector<std::uint32_t>& valid, const Eigen::Vector4f& plane,
                           const SurfaceRules& rules) {
  TableSurface surface;
  surface.plane = plane;
  surface.height.assign(points.size(), std::numeric_limits<float>::quiet_NaN());
  for (std::uint32_t i : valid) {
    surface.height[i] = signed_distance(plane, points[i]);
    if (std::abs(surface.height[i]) <= rules.band) surface.band.push_back(i);
  }
  surface.band_grid = std::make_unique<PlaneGrid>(points, surface.band, plane, rules.connectivity);
  const std::vector<std::vector<std::uint32_t>> parts = surface.band_grid->connected_parts();
  // The bulk must be a surface lying in the plane: not a strip where the plane cuts a surface at
  // a steep angle (e.g. a plane through the sensor along an image row), nor a plane slicing
  // through walls or object sides (their points in the band face sideways).
  if (parts.empty() ||
      estimate_plane(points, parts.front()).narrow_spread < rules.min_narrow_spread)
    surface.not_a_table = "a thin strip";
  else if (surface.band_grid->fraction_parallel(parts.front(), rules.normal_angle_deg) <
           rules.min_parallel)
    surface.not_a_table = "a slice through surfaces that are not parallel to it";
  if (surface.not_a_table) return surface;

  surface.is_table.assign(points.size(), 0);
  const double min_part = rules.min_part * double(parts.front().size());
  for (const auto& part : parts)
    if (double(part.size()) >= min_part)
      for (std::uint32_t i : part) surface.is_table[i] = 1;
  for (std::uint32_t i : surface.band)
    if (surface.is_table[i]) surface.inliers.push_back(i);
  surface.hull = convex_hull(surface.band_grid->hull_candidates(surface.inliers));
  return surface;
}

std::size_t support_count(const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& valid,
                          const TableSurface& surface, const SurfaceRules& rules,
                          const SupportOptions& options) {
  if (surface.not_a_table) return 0;
  std::size_t held = 0;
  HullMembership inside_hull(surface.hull, 0.0f, surface.band_grid->cell());
  for (std::size_t k = 0; k < valid.size(); k += std::size_t(options.count_stride)) {
    const std::uint32_t i = valid[k];
    const float h = surface.height[i];
    held += surface.is_table[i] || (h >= rules.min_height && h <= rules.max_height &&
                                    inside_hull.contains(surface.band_grid->project(points[i])));
  }
  return held;
}

std::vector<Eigen::Vector4f> further_horizontal_planes(
    const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& indices,
    const Eigen::Vector4f& dominant, const std::vector<std::uint32_t>& inliers,
    const PlaneFitOptions& fit_options, const SupportOptions& options, const RunContext& context) {
  std::vector<Eigen::Vector4f> planes;
  if (!options.enabled) return planes;
  PlaneFitOptions further = fit_options;
  further.axis = dominant.head<3>();
  further.max_angle_deg = options.parallel_deg;
  further.max_scoring_points = options.scoring_points;
  further.min_inliers = std::max(
      fit_options.min_inliers,
      static_cast<std::size_t>(std::ceil(options.min_point_share * double(inliers.size()))));
  std::vector<std::uint32_t> remaining;
  std::set_difference(indices.begin(), indices.end(), inliers.begin(), inliers.end(),
                      std::back_inserter(remaining));
  for (int k = 1; k < options.max_candidates && remaining.size() >= further.min_inliers; ++k) {
    const PlaneFit fit = fit_plane(points, remaining, further, context);
    if (fit.status != PlaneFitStatus::kOk) break;
    planes.push_back(fit.plane);  // fit_plane orients the normal along the axis
    std::vector<std::uint32_t> rest;
    std::set_difference(remaining.begin(), remaining.end(), fit.inliers.begin(), fit.inliers.end(),
                        std::back_inserter(rest));
    remaining = std::move(rest);
  }
  return planes;
}

}  // namespace primlabel::tabletop
