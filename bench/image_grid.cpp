#include "image_grid.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace primlabel::bench {

namespace {
// Buckets an eighth of a sphere's window (2 r / z) wide at the median depth: on mOSD learn20's
// 7 mm voxels at 30 mm a query then compares 2.3 candidates a neighbour, at a quarter 2.9.
constexpr double kBucketShare = 0.125;

// The range of x/z over a ball of radius r around (x, z), z > r: the slopes s of the two planes
// through the viewpoint tangent to it, (x - s z)^2 = r^2 (1 + s^2).
void slope_range(double x, double z, double r, double& lo, double& hi) {
  const double root = r * std::sqrt(std::max(0.0, x * x + z * z - r * r));
  const double denominator = z * z - r * r;
  lo = (x * z - root) / denominator;
  hi = (x * z + root) / denominator;
}
}  // namespace

Vec3f ImageGrid::to_sensor(const Vec3f& p) const {
  return identity_ ? p : Vec3f(to_sensor_ * (p - origin_));
}

std::int64_t ImageGrid::bucket(double v, double v0, std::int64_t count) const {
  const double c = std::floor((v - v0) * inv_bucket_);
  if (!(c >= 0.0)) return 0;
  if (!(c < double(count - 1))) return count - 1;
  return std::int64_t(c);
}

std::unique_ptr<ImageGrid> ImageGrid::build(const std::vector<Vec3f>& points, float radius,
                                            const Viewpoint& viewpoint) {
  if (!(radius > 0.0f) || !std::isfinite(radius)) return nullptr;
  auto grid = std::unique_ptr<ImageGrid>(new ImageGrid);
  grid->origin_ = viewpoint.origin;
  grid->to_sensor_ = viewpoint.orientation.normalized().toRotationMatrix().transpose();
  grid->identity_ = viewpoint.origin == Vec3f::Zero() &&
                    viewpoint.orientation.coeffs() == Eigen::Quaternionf::Identity().coeffs();
  std::vector<std::uint32_t> kept;
  std::vector<double> s, t;
  std::vector<float> depth;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!is_finite(points[i])) continue;
    const Vec3f p = grid->to_sensor(points[i]);
    if (!(p.z() > 0.0f)) return nullptr;  // on or behind the image plane: no projection
    kept.push_back(std::uint32_t(i));
    s.push_back(double(p.x()) / double(p.z()));
    t.push_back(double(p.y()) / double(p.z()));
    depth.push_back(p.z());
  }
  const std::size_t n = kept.size();
  if (n == 0) return nullptr;
  const auto [s_lo, s_hi] = std::minmax_element(s.begin(), s.end());
  const auto [t_lo, t_hi] = std::minmax_element(t.begin(), t.end());
  std::nth_element(depth.begin(), depth.begin() + std::ptrdiff_t(n / 2), depth.end());
  // Wider buckets while their count would exceed a few per point (a far outlier off the axis
  // stretches the image; every bucket costs a slot even when empty).
  double width = kBucketShare * 2.0 * double(radius) / double(depth[n / 2]);
  const double max_cells = 4.0 * double(n) + 4096;
  const auto cells = [&](double w) {
    return (std::floor((*s_hi - *s_lo) / w) + 1) * (std::floor((*t_hi - *t_lo) / w) + 1);
  };
  while (!(cells(width) <= max_cells)) width *= 2.0;
  grid->s0_ = *s_lo, grid->t0_ = *t_lo, grid->inv_bucket_ = 1.0 / width;
  grid->cols_ = std::int64_t(std::floor((*s_hi - *s_lo) * grid->inv_bucket_)) + 1;
  grid->rows_ = std::int64_t(std::floor((*t_hi - *t_lo) * grid->inv_bucket_)) + 1;
  std::vector<std::uint32_t> cell_of(n);
  grid->starts_.assign(std::size_t(grid->cols_ * grid->rows_) + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t c = grid->bucket(s[i], grid->s0_, grid->cols_);
    const std::int64_t r = grid->bucket(t[i], grid->t0_, grid->rows_);
    cell_of[i] = std::uint32_t(r * grid->cols_ + c);
    ++grid->starts_[cell_of[i] + 1];
  }
  std::partial_sum(grid->starts_.begin(), grid->starts_.end(), grid->starts_.begin());
  grid->index_.resize(n);
  grid->points_.resize(n);
  std::vector<std::uint32_t> fill(grid->starts_.begin(), grid->starts_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {  // stable: ascending index within a bucket
    const std::uint32_t slot = fill[cell_of[i]]++;
    grid->index_[slot] = kept[i];
    grid->points_[slot] = points[kept[i]];
  }
  return grid;
}

bool ImageGrid::find(const Vec3f& q_world, float radius, NeighborList& out,
                     std::size_t* candidates) const {
  if (candidates) *candidates = 0;
  if (!is_finite(q_world)) return true;
  const Vec3f q = to_sensor(q_world);
  // A point the float test keeps may lie a rounding error outside the radius, and the sensor
  // frame's coordinates carry the rotation's rounding: the window is that much wider.
  const double scale = std::max({std::fabs(double(q_world.x())), std::fabs(double(q_world.y())),
                                 std::fabs(double(q_world.z())), std::fabs(double(q.z()))});
  const double reach = double(radius) * (1.0 + 1e-5) + 1e-6 * scale;
  if (!(double(q.z()) > reach * 1.001)) return false;
  const double qx = q.x(), qy = q.y(), qz = q.z();
  double s_lo, s_hi, t_lo, t_hi;
  slope_range(qx, qz, reach, s_lo, s_hi);
  slope_range(qy, qz, reach, t_lo, t_hi);
  // The projection is the ellipse of directions (s, t, 1) within the sphere's cone: for a given t
  // its s-span solves a (s^2) + 2 b s + c >= 0 with a < 0. Its left edge is convex and its right
  // edge concave in t, so over a row's t-slab the span's ends lie at the ellipse's leftmost and
  // rightmost points (where the tangent planes above touch) when in the slab, else at the slab's
  // end nearest them.
  const double k = qx * qx + qy * qy + qz * qz - reach * reach;
  const double a = reach * reach - qy * qy - qz * qz;
  const auto span_at = [&](double tv, double& left, double& right) {
    const double m = tv * qy + qz;
    const double b = qx * m;
    const double c = m * m - k * (tv * tv + 1.0);
    const double root = std::sqrt(std::max(0.0, b * b - a * c));
    left = (-b + root) / a;
    right = (-b - root) / a;
  };
  const auto touch_t = [&](double sv) {
    const double norm2 = 1.0 + sv * sv;
    const double d = (qx - sv * qz) / norm2;  // signed distance over the normal's length
    return qy / (qz + d * sv);
  };
  const double t_left = touch_t(s_lo), t_right = touch_t(s_hi);
  const double margin = 1e-9 + 1e-7 * (std::fabs(s_lo) + std::fabs(s_hi));
  thread_local std::vector<std::pair<std::uint32_t, std::uint32_t>> runs;
  runs.clear();
  std::size_t total = 0;
  const std::int64_t r0 = bucket(t_lo, t0_, rows_), r1 = bucket(t_hi, t0_, rows_);
  for (std::int64_t r = r0; r <= r1; ++r) {
    const double ta = std::max(t_lo, t0_ + double(r) / inv_bucket_);
    const double tb = std::min(t_hi, t0_ + double(r + 1) / inv_bucket_);
    double left = s_lo, right = s_hi, unused = 0;
    if (ta <= tb) {  // else a clamped edge row: its whole span
      span_at(std::clamp(t_left, ta, tb), left, unused);
      span_at(std::clamp(t_right, ta, tb), unused, right);
      left = std::max(s_lo, left - margin);
      right = std::min(s_hi, right + margin);
    }
    const std::int64_t c0 = bucket(left, s0_, cols_), c1 = bucket(right, s0_, cols_);
    if (c0 > c1) continue;
    const std::uint32_t first = starts_[std::size_t(r * cols_ + c0)];
    const std::uint32_t last = starts_[std::size_t(r * cols_ + c1) + 1];
    if (first == last) continue;
    runs.emplace_back(first, last);
    total += last - first;
  }
  // Every candidate is written and kept if inside (branch-free), into room for all of them.
  thread_local std::vector<std::uint32_t> index_room;
  thread_local std::vector<float> sq_room;
  if (index_room.size() < total) {
    index_room.resize(std::max(total, 2 * index_room.size()));
    sq_room.resize(index_room.size());
  }
  std::uint32_t* indices = index_room.data();
  float* sq_dists = sq_room.data();
  const float sq_radius = radius * radius;
  std::size_t count = 0;
  for (const auto& [first, last] : runs)
    for (std::size_t i = first; i < last; ++i) {
      const Vec3f& p = points_[i];
      // The radius grid's and nanoflann's arithmetic: ((dx^2 + dy^2) + dz^2) < r^2.
      const float dx = q_world.x() - p.x(), dy = q_world.y() - p.y(), dz = q_world.z() - p.z();
      const float sq = (dx * dx + dy * dy) + dz * dz;
      indices[count] = index_[i];
      sq_dists[count] = sq;
      count += sq < sq_radius;
    }
  out.indices.insert(out.indices.end(), indices, indices + count);
  out.sq_dists.insert(out.sq_dists.end(), sq_dists, sq_dists + count);
  if (candidates) *candidates = total;
  return true;
}

}  // namespace primlabel::bench
