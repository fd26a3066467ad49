// Fitted shapes: their closest surface points, synthetic shapes and the evidence for a model.

#include <algorithm>
#include <cmath>

#include "shape_fit.hpp"

namespace primlabel::synth::fit {
namespace {

// Among candidate surface points, the nearest one whose surface the point's normal supports
// (when it has a normal and some candidate agrees), else the nearest: a point beside a face the
// scan never saw keeps the part its normal shows.
SurfacePoint pick(const SurfacePoint* candidates, int count, const Vec3d& normal) {
  SurfacePoint best, agreeing;
  best.distance = agreeing.distance = INFINITY;
  for (int k = 0; k < count; ++k) {
    const SurfacePoint& c = candidates[k];
    if (c.distance < best.distance) best = c;
    if (!(normal.dot(c.normal) < 0.5) && c.distance < agreeing.distance) agreeing = c;
  }
  return agreeing.part >= 0 ? agreeing : best;
}

SurfacePoint closest_on_box(const Vec3d& size, const Vec3d& p, const Vec3d& normal) {
  const Vec3d lo(-0.5 * size.x(), -0.5 * size.y(), 0.0);
  const Vec3d hi(0.5 * size.x(), 0.5 * size.y(), size.z());
  const Vec3d clamped = p.cwiseMax(lo).cwiseMin(hi);
  SurfacePoint faces[6];
  for (int part = 0; part < 6; ++part) {
    SurfacePoint& f = faces[part];
    f.part = part;
    f.point = clamped;
    f.point[part / 2] = part % 2 ? hi[part / 2] : lo[part / 2];
    f.distance = (p - f.point).norm();
    f.normal[part / 2] = part % 2 ? 1.0 : -1.0;
  }
  return pick(faces, 6, normal);
}

// Can of `radius` and `height` around the z axis, bottom at z = 0: 0 side, 1 lid, 2 bottom.
SurfacePoint closest_on_can(double radius, double height, const Vec3d& p, const Vec3d& normal) {
  const double rho = std::hypot(p.x(), p.y());
  const Eigen::Vector2d dir =
      rho > 1e-12 ? Eigen::Vector2d(p.x() / rho, p.y() / rho) : Eigen::Vector2d(1, 0);
  const double in = std::min(rho, radius);
  const Vec3d points[3] = {
      Vec3d(radius * dir.x(), radius * dir.y(), std::clamp(p.z(), 0.0, height)),
      Vec3d(in * dir.x(), in * dir.y(), height), Vec3d(in * dir.x(), in * dir.y(), 0.0)};
  const Vec3d normals[3] = {Vec3d(dir.x(), dir.y(), 0), Vec3d::UnitZ(), -Vec3d::UnitZ()};
  SurfacePoint parts[3];
  for (int part = 0; part < 3; ++part)
    parts[part] = {part, points[part], (p - points[part]).norm(), normals[part]};
  return pick(parts, 3, normal);
}

}  // namespace

SurfacePoint closest_surface(const FittedObject& object, const Vec3d& local, const Vec3d& normal) {
  switch (object.kind) {
    case FittedKind::kBox:
      return closest_on_box(object.size, local, normal);
    case FittedKind::kUprightCylinder:
      return closest_on_can(object.size.x(), object.size.y(), local, normal);
    case FittedKind::kLyingCylinder: {
      const synth::LyingCanShape can(object.size.x(), object.size.y());
      const Vec3d mirrored(normal.z(), normal.y(), normal.x());
      SurfacePoint out =
          closest_on_can(can.radius(), can.length(), can.upright_from_local(local), mirrored);
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
    const Vec3d normal = local_from_table.linear() * segment.n[i];
    const SurfacePoint sp = closest_surface(object, local_from_table * segment.p[i], normal);
    const double t = segment.bound[i];
    if (!supports(sp.distance, t, normal, sp.normal)) {
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

}  // namespace primlabel::synth::fit
