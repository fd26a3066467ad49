// Fitted shapes: their closest surface points, synthetic shapes and the evidence for a model.

#include <algorithm>
#include <cmath>

#include "truth_fit.hpp"

namespace primlabel::research::truth {
namespace {

SurfacePoint closest_on_box(const Vec3d& size, const Vec3d& p) {
  const Vec3d lo(-0.5 * size.x(), -0.5 * size.y(), 0.0);
  const Vec3d hi(0.5 * size.x(), 0.5 * size.y(), size.z());
  const Vec3d clamped = p.cwiseMax(lo).cwiseMin(hi);
  SurfacePoint out;
  if (clamped != p) {  // outside: the face beyond which the point lies farthest
    double excess = -INFINITY;
    for (int k = 0; k < 3; ++k) {
      const double below = lo[k] - p[k], above = p[k] - hi[k];
      if (below > excess) excess = below, out.part = 2 * k;
      if (above > excess) excess = above, out.part = 2 * k + 1;
    }
    out.point = clamped;
    out.distance = (p - clamped).norm();
    out.normal[out.part / 2] = out.part % 2 ? 1.0 : -1.0;
    return out;
  }
  out.distance = INFINITY;  // inside: the nearest face
  for (int k = 0; k < 3; ++k) {
    if (p[k] - lo[k] < out.distance) out.distance = p[k] - lo[k], out.part = 2 * k;
    if (hi[k] - p[k] < out.distance) out.distance = hi[k] - p[k], out.part = 2 * k + 1;
  }
  out.point = p;
  out.point[out.part / 2] = out.part % 2 ? hi[out.part / 2] : lo[out.part / 2];
  out.normal[out.part / 2] = out.part % 2 ? 1.0 : -1.0;
  return out;
}

// Can of `radius` and `height` around the z axis, bottom at z = 0: 0 side, 1 lid, 2 bottom.
SurfacePoint closest_on_can(double radius, double height, const Vec3d& p) {
  const double rho = std::hypot(p.x(), p.y());
  const Eigen::Vector2d dir =
      rho > 1e-12 ? Eigen::Vector2d(p.x() / rho, p.y() / rho) : Eigen::Vector2d(1, 0);
  const double in = std::min(rho, radius);
  const Vec3d candidates[3] = {
      Vec3d(radius * dir.x(), radius * dir.y(), std::clamp(p.z(), 0.0, height)),
      Vec3d(in * dir.x(), in * dir.y(), height), Vec3d(in * dir.x(), in * dir.y(), 0.0)};
  const Vec3d normals[3] = {Vec3d(dir.x(), dir.y(), 0), Vec3d::UnitZ(), -Vec3d::UnitZ()};
  SurfacePoint out;
  out.distance = INFINITY;
  for (int part = 0; part < 3; ++part) {
    const double d = (p - candidates[part]).norm();
    if (d < out.distance) out = {part, candidates[part], d, normals[part]};
  }
  return out;
}

}  // namespace

SurfacePoint closest_surface(const FittedObject& object, const Vec3d& local) {
  switch (object.kind) {
    case FittedKind::kBox:
      return closest_on_box(object.size, local);
    case FittedKind::kUprightCylinder:
      return closest_on_can(object.size.x(), object.size.y(), local);
    case FittedKind::kLyingCylinder: {
      const synth::LyingCanShape can(object.size.x(), object.size.y());
      SurfacePoint out = closest_on_can(can.radius(), can.length(), can.upright_from_local(local));
      out.point = can.local_from_upright(out.point);
      out.normal = Vec3d(out.normal.z(), out.normal.y(), out.normal.x());  // the mirror
      return out;
    }
    case FittedKind::kUnfitted:
      break;
  }
  return {-1, local, INFINITY};
}

std::shared_ptr<const synth::Shape> make_shape(const FittedObject& object) {
  switch (object.kind) {
    case FittedKind::kBox:
      // Bottom edges stay out as for every synthetic box: the objects stand on something.
      return std::make_shared<synth::BoxShape>(object.size);
    case FittedKind::kUprightCylinder:
      return std::make_shared<synth::CanShape>(object.size.x(), object.size.y());
    case FittedKind::kLyingCylinder:
      return std::make_shared<synth::LyingCanShape>(object.size.x(), object.size.y());
    case FittedKind::kUnfitted:
      break;
  }
  return nullptr;
}

Evidence evaluate(const FittedObject& object, const SegmentPoints& segment) {
  Evidence e;
  if (segment.p.empty()) return e;
  const Eigen::Isometry3d local_from_table = object.table_from_local.inverse();
  double cost = 0, squares = 0;
  for (std::size_t i = 0; i < segment.p.size(); ++i) {
    const SurfacePoint sp = closest_surface(object, local_from_table * segment.p[i]);
    const double t = segment.bound[i];
    if (!supports(sp.distance, t, local_from_table.linear() * segment.n[i], sp.normal)) {
      cost += 1;
      continue;
    }
    cost += sp.distance * sp.distance / (t * t);
    ++e.inliers;
    squares += sp.distance * sp.distance;
  }
  e.cost = cost / double(segment.p.size());
  e.rms = e.inliers ? std::sqrt(squares / double(e.inliers)) : 0.0;
  return e;
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return NAN;
  const std::size_t k =
      std::min(values.size() - 1, static_cast<std::size_t>(q * double(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace primlabel::research::truth
