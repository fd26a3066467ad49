#include "fit_support.hpp"

#include <Eigen/Eigenvalues>

namespace primlabel::primitives::detail {

Points gather(const SegmentPoints& points) {
  Points out;
  out.p.reserve(points.indices.size());
  out.n.reserve(points.indices.size());
  for (std::uint32_t index : points.indices) {
    if (index >= points.xyz.size() || !is_finite(points.xyz[index])) continue;
    Vec3d normal = Vec3d::Constant(NAN);
    if (index < points.normals.size() && is_finite(points.normals[index])) {
      const Vec3d n = points.normals[index].cast<double>();
      if (n.norm() > 1e-6) normal = n.normalized();
    }
    if (std::isfinite(normal.x())) out.with_normal.push_back(out.p.size());
    out.p.push_back(points.xyz[index].cast<double>());
    out.n.push_back(normal);
  }
  return out;
}

std::vector<std::size_t> strided(std::size_t n, std::size_t max) {
  std::vector<std::size_t> out;
  if (n == 0 || max == 0) return out;
  const std::size_t stride = (n + max - 1) / max;
  for (std::size_t i = 0; i < n; i += stride) out.push_back(i);
  return out;
}

std::vector<std::size_t> strided(const std::vector<std::size_t>& from, std::size_t max) {
  std::vector<std::size_t> out;
  for (std::size_t k : strided(from.size(), max)) out.push_back(from[k]);
  return out;
}

std::vector<Vec3d> refine_points(const Points& pts, const std::vector<std::size_t>& indices,
                                 const FitSettings& settings) {
  std::vector<Vec3d> out;
  for (std::size_t i : strided(indices, settings.max_refine_points)) out.push_back(pts.p[i]);
  return out;
}

double arc_span(const Points& pts, const std::vector<std::size_t>& indices, const Vec3d& center,
                const Vec3d& axis) {
  if (indices.size() < 2) return 0;
  // 5 degree sectors; one counts as seen when it holds a tenth of an even share of the points,
  // so a few stray inliers across the axis do not make a half-seen can look whole.
  constexpr int kSectors = 72;
  const auto [u, v] = frame(axis);
  std::vector<std::size_t> counts(kSectors, 0);
  for (std::size_t i : indices) {
    const Vec3d q = pts.p[i] - center;
    const double angle = std::atan2(q.dot(v), q.dot(u)) + M_PI;  // [0, 2 pi]
    ++counts[std::min(kSectors - 1, int(angle / (2 * M_PI) * kSectors))];
  }
  const double min_count = std::max(1.0, 0.1 * double(indices.size()) / kSectors);
  int longest_empty = 0, run = 0;
  for (int k = 0; k < 2 * kSectors; ++k) {  // twice round: runs across the seam
    if (double(counts[k % kSectors]) < min_count) {
      longest_empty = std::max(longest_empty, std::min(++run, kSectors));
    } else {
      run = 0;
    }
  }
  return 2 * M_PI * double(kSectors - longest_empty) / kSectors;
}

double cap_half_angle(const Points& pts, const std::vector<std::size_t>& indices,
                      const Vec3d& center) {
  Vec3d mean = Vec3d::Zero();
  for (std::size_t i : indices) mean += (pts.p[i] - center).normalized();
  if (!(mean.norm() > 1e-9 * double(indices.size()))) return M_PI;  // points all round
  mean.normalize();
  std::vector<double> angles;
  angles.reserve(indices.size());
  for (std::size_t i : indices)
    angles.push_back(std::acos(std::clamp((pts.p[i] - center).normalized().dot(mean), -1.0, 1.0)));
  if (angles.empty()) return 0;
  // The 95th percentile: stray inliers on the far side do not widen the cap.
  const std::size_t k = std::min(angles.size() - 1, std::size_t(0.95 * double(angles.size())));
  std::nth_element(angles.begin(), angles.begin() + std::ptrdiff_t(k), angles.end());
  return angles[k];
}

PlaneEstimate estimate_plane(const Points& pts, const std::vector<std::size_t>& indices) {
  PlaneEstimate out;
  if (indices.size() < 3) return out;
  Vec3d sum = Vec3d::Zero();
  for (std::size_t i : indices) sum += pts.p[i];
  out.centroid = sum / double(indices.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i : indices) {
    const Vec3d q = pts.p[i] - out.centroid;
    covariance += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  if (solver.info() != Eigen::Success || !solver.eigenvectors().allFinite()) return out;
  // Eigen sorts eigenvalues ascending: the smallest is the normal.
  out.normal = solver.eigenvectors().col(0);
  out.axes.col(0) = solver.eigenvectors().col(2);
  out.axes.col(1) = solver.eigenvectors().col(1);
  out.axes.col(2) = out.normal;
  return out;
}

}  // namespace primlabel::primitives::detail
