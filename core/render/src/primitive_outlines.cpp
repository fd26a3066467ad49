// Outlines of fitted primitives (see primitive_outlines.hpp): polylines sampled from each
// model's parameters, in float for the renderer.

#include "primlabel/render/primitive_outlines.hpp"

#include <cmath>

#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel {
namespace {

using primitives::Vec3d;

struct Outliner {
  const OutlineOptions& options;
  std::uint32_t rgb;
  std::vector<Overlay>& out;

  bool usable(double size) const { return std::isfinite(size) && size >= options.min_extent; }

  void polyline(std::vector<Vec3d> points, bool closed) {
    Overlay overlay;
    overlay.rgb = rgb;
    overlay.closed = closed;
    overlay.points.reserve(points.size());
    for (const Vec3d& p : points) overlay.points.push_back(p.cast<float>());
    out.push_back(std::move(overlay));
  }
  void segment(const Vec3d& a, const Vec3d& b) { polyline({a, b}, false); }

  // The circle of `radius` around `axis` (unit) through `center`.
  void circle(const Vec3d& center, const Vec3d& axis, double radius) {
    const auto [u, v] = basis(axis);
    std::vector<Vec3d> points;
    const int n = std::max(options.circle_segments, 8);
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      points.push_back(center + radius * (std::cos(a) * u + std::sin(a) * v));
    }
    polyline(std::move(points), true);
  }

  static std::pair<Vec3d, Vec3d> basis(const Vec3d& axis) {
    const Vec3d trial = std::abs(axis.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY();
    const Vec3d u = (trial - trial.dot(axis) * axis).normalized();
    return {u, axis.cross(u)};
  }

  void operator()(std::monostate) {}

  void operator()(const primitives::PlaneModel& m) {
    if (!usable(m.extent_u) || !usable(m.extent_v)) return;
    const Vec3d u = 0.5 * m.extent_u * m.axis_u, v = 0.5 * m.extent_v * m.axis_v;
    polyline({m.center - u - v, m.center + u - v, m.center + u + v, m.center - u + v}, true);
    // The normal as a tick a tenth of the plane's size, so its side reads in the picture.
    segment(m.center, m.center + 0.1 * std::max(m.extent_u, m.extent_v) * m.normal);
  }

  void operator()(const primitives::CylinderModel& m) {
    if (!usable(m.radius) || !usable(m.height)) return;
    const Vec3d half = 0.5 * m.height * m.axis;
    circle(m.center - half, m.axis, m.radius);
    circle(m.center + half, m.axis, m.radius);
    const auto [u, v] = basis(m.axis);
    for (const Vec3d& side : {u, v, Vec3d(-u), Vec3d(-v)})
      segment(m.center - half + m.radius * side, m.center + half + m.radius * side);
    segment(m.center - half, m.center + half);
  }

  void operator()(const primitives::SphereModel& m) {
    if (!usable(m.radius)) return;
    circle(m.center, Vec3d::UnitX(), m.radius);
    circle(m.center, Vec3d::UnitY(), m.radius);
    circle(m.center, Vec3d::UnitZ(), m.radius);
  }

  void operator()(const primitives::TorusModel& m) {
    if (!usable(m.major_radius) || !usable(m.minor_radius)) return;
    // The tube's silhouette seen along the axis and from the side.
    circle(m.center, m.axis, m.major_radius + m.minor_radius);
    if (m.major_radius > m.minor_radius) circle(m.center, m.axis, m.major_radius - m.minor_radius);
    circle(m.center + m.minor_radius * m.axis, m.axis, m.major_radius);
    circle(m.center - m.minor_radius * m.axis, m.axis, m.major_radius);
    segment(m.center - m.minor_radius * m.axis, m.center + m.minor_radius * m.axis);
  }

  void operator()(const primitives::LineModel& m) {
    if (!usable(m.length)) return;
    segment(m.center - 0.5 * m.length * m.direction, m.center + 0.5 * m.length * m.direction);
  }
};

std::uint32_t darkened(std::uint32_t rgb) {
  auto channel = [&](int shift) { return (((rgb >> shift) & 0xFF) * 45 / 100) << shift; };
  return channel(16) | channel(8) | channel(0);
}

}  // namespace

std::vector<Overlay> primitive_outlines(std::span<const primitives::Primitive> fitted,
                                        const OutlineOptions& options) {
  std::vector<Overlay> out;
  for (const primitives::Primitive& p : fitted) {
    if (!(p.confidence >= options.min_confidence)) continue;
    const auto cls = class_from_id(p.class_id);
    const std::uint32_t rgb = darkened(cls ? color(*cls) : 0x404040);
    std::visit(Outliner{options, rgb, out}, p.model);
  }
  return out;
}

}  // namespace primlabel
