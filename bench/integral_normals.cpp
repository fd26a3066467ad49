#include "integral_normals.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace primlabel::bench {

IntegralMoments::IntegralMoments(const PointCloud& frame)
    : width_(int(frame.width)), height_(int(frame.height)) {
  if (!frame.organized() || std::size_t(frame.width) * frame.height != frame.size())
    throw std::invalid_argument("integral-image normals need an organised frame");
  double sum[3] = {0, 0, 0};
  std::size_t finite = 0;
  for (const Vec3f& p : frame.xyz)
    if (is_finite(p)) {
      for (int d = 0; d < 3; ++d) sum[d] += p[d];
      ++finite;
    }
  if (finite > 0)
    centre_ = Vec3f(float(sum[0] / double(finite)), float(sum[1] / double(finite)),
                    float(sum[2] / double(finite)));
  sums_.assign(std::size_t(width_ + 1) * std::size_t(height_ + 1) * kMoments, 0.0);
  for (int v = 0; v < height_; ++v) {
    double row[kMoments] = {};
    for (int u = 0; u < width_; ++u) {
      const Vec3f& p = frame.xyz[std::size_t(v) * std::size_t(width_) + std::size_t(u)];
      if (is_finite(p)) {
        const double x = p.x() - centre_.x(), y = p.y() - centre_.y(), z = p.z() - centre_.z();
        const double m[kMoments] = {1, x, y, z, x * x, x * y, x * z, y * y, y * z, z * z};
        for (int k = 0; k < kMoments; ++k) row[k] += m[k];
      }
      const double* above = at(u + 1, v);
      double* out = sums_.data() +
                    (std::size_t(v + 1) * std::size_t(width_ + 1) + std::size_t(u + 1)) * kMoments;
      for (int k = 0; k < kMoments; ++k) out[k] = above[k] + row[k];
    }
  }
}

bool IntegralMoments::normal(int u0, int v0, int u1, int v1, const Vec3f& viewpoint, Vec3f& normal,
                             float& variation) const {
  u0 = std::max(u0, 0), v0 = std::max(v0, 0);
  u1 = std::min(u1, width_ - 1), v1 = std::min(v1, height_ - 1);
  if (u0 > u1 || v0 > v1) return false;
  const double *a = at(u1 + 1, v1 + 1), *b = at(u0, v1 + 1), *c = at(u1 + 1, v0), *d = at(u0, v0);
  double m[kMoments];
  for (int k = 0; k < kMoments; ++k) m[k] = (a[k] - b[k]) - (c[k] - d[k]);
  const double n = m[0];
  if (n < 3.0) return false;
  const double mx = m[1] / n, my = m[2] / n, mz = m[3] / n;
  Eigen::Matrix3d cov;
  cov(0, 0) = m[4] / n - mx * mx;
  cov(0, 1) = cov(1, 0) = m[5] / n - mx * my;
  cov(0, 2) = cov(2, 0) = m[6] / n - mx * mz;
  cov(1, 1) = m[7] / n - my * my;
  cov(1, 2) = cov(2, 1) = m[8] / n - my * mz;
  cov(2, 2) = m[9] / n - mz * mz;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(cov);
  const Eigen::Vector3d lambda = solver.eigenvalues();  // ascending
  const double total = lambda.sum();
  if (!(total > 0.0)) return false;
  normal = solver.eigenvectors().col(0).cast<float>();
  const Vec3f mean = centre_ + Vec3f(float(mx), float(my), float(mz));
  if ((viewpoint - mean).dot(normal) < 0.0f) normal = -normal;  // face the sensor
  variation = float(std::max(0.0, lambda(0)) / total);
  return true;
}

float estimate_focal(const PointCloud& frame) {
  const Vec3f& o = frame.viewpoint.origin;
  const Eigen::Matrix3f to_sensor =
      frame.viewpoint.orientation.normalized().toRotationMatrix().transpose();
  // Per axis the least-squares line pixel = f * ratio + c; f is their mean slope.
  double n = 0, sr[2] = {}, sp[2] = {}, srr[2] = {}, srp[2] = {};
  const std::size_t width = std::max<std::size_t>(1, frame.width);
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (!is_finite(frame.xyz[i])) continue;
    const Vec3f p = to_sensor * (frame.xyz[i] - o);
    if (!(p.z() > 0.0f)) continue;
    const double ratio[2] = {double(p.x()) / p.z(), double(p.y()) / p.z()};
    const double pixel[2] = {double(i % width), double(i / width)};
    ++n;
    for (int d = 0; d < 2; ++d) {
      sr[d] += ratio[d], sp[d] += pixel[d];
      srr[d] += ratio[d] * ratio[d], srp[d] += ratio[d] * pixel[d];
    }
  }
  if (n < 16) return std::numeric_limits<float>::quiet_NaN();
  double focal = 0;
  for (int d = 0; d < 2; ++d) focal += (n * srp[d] - sr[d] * sp[d]) / (n * srr[d] - sr[d] * sr[d]);
  return float(focal / 2.0);
}

std::vector<std::uint32_t> voxel_pixels(const PointCloud& frame,
                                        const tabletop::VoxelGrid& voxels) {
  const std::size_t width = std::max<std::size_t>(1, frame.width);
  std::vector<std::uint32_t> pixels(voxels.centroids.size(), 0);
  for (std::size_t v = 0; v < pixels.size(); ++v) {
    const std::uint32_t first = voxels.member_offsets[v], last = voxels.member_offsets[v + 1];
    if (first == last) continue;
    double su = 0, sv = 0;
    for (std::uint32_t k = first; k < last; ++k)
      su += double(voxels.members[k] % width), sv += double(voxels.members[k] / width);
    const double members = double(last - first);
    pixels[v] =
        std::uint32_t(std::lround(sv / members) * double(width) + std::lround(su / members));
  }
  return pixels;
}

namespace {
// The window's half-size: the pixels a sphere of `radius` spans at distance `distance`, at most
// the whole image (a point at the sensor would ask for more).
int half_window(float radius, float focal, float distance) {
  const float reach = radius * focal / distance;
  return std::isfinite(reach) ? int(std::clamp(std::lround(reach), 1L, 1L << 12)) : 1;
}
}  // namespace

std::vector<Vec3f> integral_pixel_normals(const PointCloud& frame, const IntegralMoments& moments,
                                          float radius, float focal) {
  std::vector<Vec3f> normals(frame.size(),
                             Vec3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  const std::size_t width = std::max<std::size_t>(1, frame.width);
  const Vec3f& viewpoint = frame.viewpoint.origin;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (!is_finite(frame.xyz[i])) continue;
    const int u = int(i % width), row = int(i / width);
    const int half = half_window(radius, focal, (frame.xyz[i] - viewpoint).norm());
    float variation = 0.0f;
    moments.normal(u - half, row - half, u + half, row + half, viewpoint, normals[i], variation);
  }
  return normals;
}

VoxelNormals integral_voxel_normals(const PointCloud& frame, const IntegralMoments& moments,
                                    const tabletop::VoxelGrid& voxels,
                                    const std::vector<std::uint32_t>& pixels, float radius,
                                    float focal) {
  const std::size_t count = voxels.centroids.size();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  VoxelNormals out{std::vector<Vec3f>(count, Vec3f::Constant(nan)), std::vector<float>(count, nan)};
  const std::size_t width = std::max<std::size_t>(1, frame.width);
  const Vec3f& viewpoint = frame.viewpoint.origin;
  for (std::size_t v = 0; v < count; ++v) {
    const int u = int(pixels[v] % width), row = int(pixels[v] / width);
    const int half = half_window(radius, focal, (voxels.centroids[v] - viewpoint).norm());
    moments.normal(u - half, row - half, u + half, row + half, viewpoint, out.normals[v],
                   out.variation[v]);
  }
  return out;
}

}  // namespace primlabel::bench
