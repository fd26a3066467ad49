// Edges: a band of points on the two faces of a crease (its width is the labels' scale, not the
// noise), so the line is where the band's two dominant planes meet: MSAC plane, MSAC plane on
// what it left, their intersection, clipped to the inliers' extent along it. With one plane only
// (a curved edge, a band seen on one face) the line is that plane's principal in-plane axis
// through the inliers' centroid, at half the confidence.

#include "fit_support.hpp"

namespace primlabel::primitives {

using namespace detail;

std::optional<Fit> fit_line(const SegmentPoints& points, const FitSettings& settings,
                            std::uint64_t seed) {
  const Points pts = gather(points);
  if (pts.size() < 6) return std::nullopt;
  std::vector<std::size_t> all(pts.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  Sampler rng(mix_seed(seed, 5));
  const auto first = msac_plane(pts, all, settings, rng);
  if (!first) return std::nullopt;
  std::vector<bool> taken(pts.size(), false);
  for (std::size_t i : first->inliers.indices) taken[i] = true;
  std::vector<std::size_t> rest;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (!taken[i]) rest.push_back(i);
  auto second = msac_plane(pts, rest, settings, rng);
  // A second face: enough points, and at an angle to the first (not a parallel slice of it).
  const std::size_t min_face = std::max<std::size_t>(6, pts.size() / 20);
  if (second && (second->inliers.indices.size() < min_face ||
                 first->normal.cross(second->normal).norm() < std::sin(20 * kDeg)))
    second.reset();

  LineModel model;
  Fit fit;
  std::vector<std::size_t> inliers = first->inliers.indices;
  double squares = first->inliers.rms * first->inliers.rms * double(inliers.size());
  if (second) {
    const Vec3d& n1 = first->normal;
    const Vec3d& n2 = second->normal;
    model.direction = n1.cross(n2).normalized();
    inliers.insert(inliers.end(), second->inliers.indices.begin(), second->inliers.indices.end());
    squares += second->inliers.rms * second->inliers.rms * double(second->inliers.indices.size());
    Vec3d centroid = Vec3d::Zero();
    for (std::size_t i : inliers) centroid += pts.p[i];
    centroid /= double(inliers.size());
    // The point of the line nearest the inliers' centroid.
    Eigen::Matrix3d m;
    m.row(0) = n1.transpose();
    m.row(1) = n2.transpose();
    m.row(2) = model.direction.transpose();
    const Vec3d rhs(-first->offset, -second->offset, model.direction.dot(centroid));
    model.center = m.colPivHouseholderQr().solve(rhs);
  } else {
    const PlaneEstimate estimate = estimate_plane(pts, inliers);
    const Vec3d& n = first->normal;
    Vec3d u = estimate.axes.col(0) - estimate.axes.col(0).dot(n) * n;
    if (!(u.norm() > 1e-9)) u = n.unitOrthogonal();
    model.direction = u.normalized();
    model.center = estimate.centroid;
  }
  if (!model.center.allFinite() || !model.direction.allFinite()) return std::nullopt;
  Eigen::Index largest;
  model.direction.cwiseAbs().maxCoeff(&largest);
  if (model.direction[largest] < 0) model.direction = -model.direction;
  double lo = INFINITY, hi = -INFINITY;
  for (std::size_t i : inliers) {
    const double along = (pts.p[i] - model.center).dot(model.direction);
    lo = std::min(lo, along), hi = std::max(hi, along);
  }
  model.center += 0.5 * (lo + hi) * model.direction;
  model.length = hi - lo;
  fit.model = model;
  fit.inliers = inliers.size();
  fit.rms = std::sqrt(squares / double(inliers.size()));
  fit.confidence = double(inliers.size()) / double(pts.size()) * (second ? 1.0 : 0.5);
  return fit;
}

}  // namespace primlabel::primitives
