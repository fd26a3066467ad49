// Planes: MSAC over three-point hypotheses, then alternating inlier selection and the
// least-squares (PCA) plane; the extent is the inliers' minimum-area bounding rectangle, whose
// longer side is axis_u.

#include "fit_support.hpp"
#include "primlabel/geometry/convex_hull.hpp"

namespace primlabel::primitives {
namespace detail {
namespace {

Deviation plane_deviation(const Vec3d& normal, double offset, const Vec3d& p) {
  return {normal.dot(p) + offset, normal};
}

}  // namespace

std::optional<PlaneHypothesis> msac_plane(const Points& pts,
                                          const std::vector<std::size_t>& candidates,
                                          const FitSettings& settings, Sampler& rng) {
  const std::size_t n = candidates.size();
  if (n < 3) return std::nullopt;
  const std::vector<std::size_t> scoring = strided(candidates, settings.max_scoring_points);
  PlaneHypothesis best;
  double best_cost = INFINITY;
  for (int h = 0; h < settings.hypotheses; ++h) {
    const Vec3d& a = pts.p[candidates[rng.below(n)]];
    const Vec3d& b = pts.p[candidates[rng.below(n)]];
    const Vec3d& c = pts.p[candidates[rng.below(n)]];
    const Vec3d cross = (b - a).cross(c - a);
    // Nearly collinear samples give no direction worth scoring.
    if (!(cross.norm() > 1e-6 * (b - a).norm() * (c - a).norm()) || cross.norm() == 0) continue;
    const Vec3d normal = cross.normalized();
    const double offset = -normal.dot(a);
    const double cost = msac_cost(
        pts, scoring, [&](const Vec3d& p) { return plane_deviation(normal, offset, p); }, settings);
    if (cost < best_cost) best_cost = cost, best.normal = normal, best.offset = offset;
  }
  if (!std::isfinite(best_cost)) return std::nullopt;
  // Inliers among the candidates only.
  auto select = [&] {
    InlierSet out;
    const double min_cos = std::cos(settings.normal_angle_deg * kDeg);
    double squares = 0;
    for (std::size_t i : candidates) {
      const double d = best.normal.dot(pts.p[i]) + best.offset;
      if (std::abs(d) < settings.distance_threshold && agrees(pts, i, best.normal, min_cos)) {
        out.indices.push_back(i);
        squares += d * d;
      }
    }
    out.rms = out.indices.empty() ? 0.0 : std::sqrt(squares / double(out.indices.size()));
    return out;
  };
  best.inliers = select();
  for (int round = 0; round < 3 && best.inliers.indices.size() >= 3; ++round) {
    const PlaneEstimate estimate =
        estimate_plane(pts, strided(best.inliers.indices, settings.max_refine_points));
    if (!estimate.normal.allFinite()) break;
    best.normal = estimate.normal;
    best.offset = -best.normal.dot(estimate.centroid);
    best.inliers = select();
  }
  if (best.inliers.indices.size() < 3) return std::nullopt;
  return best;
}

}  // namespace detail

using namespace detail;

std::optional<Fit> fit_plane(const SegmentPoints& points, const FitSettings& settings,
                             std::uint64_t seed) {
  const Points pts = gather(points);
  std::vector<std::size_t> all(pts.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  Sampler rng(mix_seed(seed, 1));
  const auto plane = msac_plane(pts, all, settings, rng);
  if (!plane) return std::nullopt;
  Vec3d normal = plane->normal;
  double offset = plane->offset;
  const std::vector<std::size_t>& inliers = plane->inliers.indices;
  // Facing the points' own normals where they have them, so the normal's sign means something.
  double facing = 0;
  for (std::size_t i : inliers)
    if (pts.has_normal(i)) facing += pts.n[i].dot(normal);
  if (facing < 0) normal = -normal, offset = -offset;

  const PlaneEstimate axes = estimate_plane(pts, inliers);
  PlaneModel model;
  model.normal = normal;
  model.offset = offset;
  Vec3d u = axes.axes.col(0) - axes.axes.col(0).dot(normal) * normal;
  if (!(u.norm() > 1e-9)) u = normal.unitOrthogonal();
  model.axis_u = u.normalized();
  model.axis_v = normal.cross(model.axis_u);
  // The smallest rectangle around the inliers, not the box along their principal axes: those
  // are arbitrary for a near-square table (and tilted by uneven density), and such a box can be
  // twice the table's area.
  std::vector<Eigen::Vector2f> in_plane(inliers.size());
  for (std::size_t k = 0; k < inliers.size(); ++k) {
    const Vec3d q = pts.p[inliers[k]] - axes.centroid;
    in_plane[k] = Eigen::Vector2d(q.dot(model.axis_u), q.dot(model.axis_v)).cast<float>();
  }
  const Rectangle2 box = min_area_rectangle(convex_hull(std::move(in_plane)));
  const Vec3d u_axis = box.axis_u.x() * model.axis_u + box.axis_u.y() * model.axis_v;
  const Vec3d middle =
      axes.centroid + box.center.x() * model.axis_u + box.center.y() * model.axis_v;
  model.center = middle - (normal.dot(middle) + offset) * normal;
  model.axis_u = (u_axis - u_axis.dot(normal) * normal).normalized();
  model.axis_v = normal.cross(model.axis_u);  // u x v = normal
  model.extent_u = box.length;
  model.extent_v = box.width;
  Fit fit;
  fit.model = model;
  fit.inliers = inliers.size();
  fit.rms = plane->inliers.rms;
  fit.confidence = double(fit.inliers) / double(pts.size());
  return fit;
}

}  // namespace primlabel::primitives
