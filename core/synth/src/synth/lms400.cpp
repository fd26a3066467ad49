// The SICK LMS400 line scanner on a tilting arm.

#include <cmath>
#include <vector>

#include "primlabel/geometry/parallel.hpp"
#include "primlabel/synth/random.hpp"
#include "primlabel/synth/scanners.hpp"
#include "scan_common.hpp"

namespace primlabel::synth {
namespace {

constexpr std::uint64_t kLms400Stream = 101;
constexpr double kDeg = M_PI / 180.0;

}  // namespace

Lms400Options lms400_for_scene(const Scene& scene, std::uint64_t seed,
                               const SensorPlacement& placement) {
  Rng rng(mix_seed(seed, kLms400Stream - 1));
  Lms400Options options;
  const double front = -0.5 * scene.table_size.y(), back = 0.5 * scene.table_size.y();
  const double side = 0.5 * scene.table_size.x();
  options.position =
      Vec3d(rng.uniform(-0.05, 0.05), front - rng.uniform(0.38, 0.45), rng.uniform(0.62, 0.70));
  options.heading_deg = 90 + rng.uniform(-3.0, 3.0);
  options.position =
      detail::place_sensor(options.position, front, placement.range_scale, placement.elevation_deg);

  // Like the arm in the paper, sweep the part of the table the objects stand on (with a margin
  // of table around them), not the whole table.
  double x_lo = -0.3, x_hi = 0.3, y_lo = front, y_hi = front + 0.4;
  for (const SceneObject& object : scene.objects) {
    if (!object.on_support) continue;
    const double r = object.shape->footprint_radius();
    x_lo = std::min(x_lo, object.bound_center.x() - r),
    x_hi = std::max(x_hi, object.bound_center.x() + r);
    y_lo = std::min(y_lo, object.bound_center.y() - r),
    y_hi = std::max(y_hi, object.bound_center.y() + r);
  }
  x_lo = std::max(x_lo - 0.06, -side), x_hi = std::min(x_hi + 0.06, side);
  y_lo = std::max(front - 0.02, std::min(y_lo - 0.06, front + 0.1));
  y_hi = std::min(y_hi + 0.06, back);

  const Vec3d& s = options.position;
  options.pitch_near_deg = std::atan2(s.z(), y_lo - s.y()) / kDeg;
  options.pitch_far_deg = std::atan2(s.z(), y_hi - s.y()) / kDeg;
  options.lines = static_cast<int>(std::ceil((options.pitch_near_deg - options.pitch_far_deg) /
                                             options.pitch_step_deg)) +
                  1;
  // The fan must reach both sides of the region on its nearest line (where it is widest).
  double half_fov = 0;
  for (double x : {x_lo, x_hi})
    for (double y : {y_lo, y_hi})
      half_fov = std::max(half_fov, std::atan2(std::abs(x - s.x()), std::hypot(s.z(), y - s.y())));
  options.fov_deg = std::min(70.0, 2.0 * half_fov / kDeg + 4.0);
  return options;
}

PointCloud scan_lms400(const Scene& scene, const Lms400Options& options, double label_radius,
                       std::uint64_t seed) {
  const double heading = options.heading_deg * kDeg;
  const Vec3d level_forward(std::cos(heading), std::sin(heading), 0.0);
  const Vec3d right(std::sin(heading), -std::cos(heading), 0.0);  // the tilt axis
  const int per_line = static_cast<int>(std::floor(options.fov_deg / options.angular_step_deg)) + 1;
  const int lines = std::max(options.lines, 1);
  const double min_cos_incidence = std::cos(options.max_incidence_deg * kDeg);

  std::vector<std::vector<detail::Return>> line_returns(lines);
  primlabel::detail::parallel_for(
      lines, 0, primlabel::detail::Schedule::Dynamic(4), [&](std::ptrdiff_t line) {
        const double fraction = lines > 1 ? double(line) / double(lines - 1) : 0.5;
        const double pitch =
            (options.pitch_near_deg + fraction * (options.pitch_far_deg - options.pitch_near_deg)) *
            kDeg;
        const Vec3d forward = std::cos(pitch) * level_forward - std::sin(pitch) * Vec3d::UnitZ();
        std::vector<detail::Return>& out = line_returns[line];
        for (int k = 0; k < per_line; ++k) {
          const double theta = (-0.5 * options.fov_deg + k * options.angular_step_deg) * kDeg;
          const Ray ray{options.position,
                        (std::cos(theta) * forward + std::sin(theta) * right).normalized()};
          Rng rng(mix_seed(seed, kLms400Stream, std::uint64_t(line) * per_line + k));
          const double lost = rng.uniform();
          const double noise = rng.normal();

          const auto hit = scene.cast(ray, 1e-6, options.max_range);
          if (!hit || hit->t < options.min_range || lost < options.dropout) continue;
          if (-ray.dir.dot(hit->normal) < min_cos_incidence) continue;
          const Vec3d point = ray.at(hit->t);
          const Vec3d measured = ray.at(hit->t + options.range_noise * noise);
          out.push_back(detail::make_return(scene, *hit, point, measured, label_radius));
        }
      });

  std::vector<detail::Return> returns;
  for (auto& line : line_returns) returns.insert(returns.end(), line.begin(), line.end());
  PointCloud cloud;
  detail::label_unseen_creases_as_surface(returns, label_radius);
  detail::store_returns(returns, cloud);
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  const double mid_pitch = 0.5 * (options.pitch_near_deg + options.pitch_far_deg) * kDeg;
  const Vec3d look = std::cos(mid_pitch) * level_forward - std::sin(mid_pitch) * Vec3d::UnitZ();
  cloud.viewpoint.origin = options.position.cast<float>();
  cloud.viewpoint.orientation = Eigen::Quaternionf(detail::camera_rotation(look).cast<float>());
  return cloud;
}

}  // namespace primlabel::synth
