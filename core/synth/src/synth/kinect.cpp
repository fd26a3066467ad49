// The Kinect-like structured-light depth camera.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "primlabel/geometry/parallel.hpp"
#include "primlabel/synth/random.hpp"
#include "primlabel/synth/scanners.hpp"
#include "scan_common.hpp"

namespace primlabel::synth {
namespace {

constexpr std::uint64_t kKinectStream = 201;
constexpr std::uint64_t kCorrelatedStream = 202;
constexpr double kDeg = M_PI / 180.0;

// Unit-variance white noise per pixel (its own stream), blurred by a separable Gaussian of std
// `sigma_px` and rescaled to unit variance again (per pixel, so the image border keeps it).
std::vector<double> correlated_field(int width, int height, double sigma_px, std::uint64_t seed) {
  const int radius = static_cast<int>(std::ceil(3.0 * sigma_px));
  std::vector<double> kernel(2 * radius + 1);
  for (int k = -radius; k <= radius; ++k)
    kernel[k + radius] = std::exp(-0.5 * k * k / (sigma_px * sigma_px));
  const std::size_t pixels = std::size_t(width) * height;
  std::vector<double> white(pixels), rows(pixels), rows_sq(pixels), out(pixels);
  for (std::size_t i = 0; i < pixels; ++i)
    white[i] = Rng(mix_seed(seed, kCorrelatedStream, i)).normal();
  // Along rows, then along columns; the squared weights give the variance to divide out.
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      double sum = 0, sq = 0;
      for (int k = std::max(-radius, -u); k <= std::min(radius, width - 1 - u); ++k) {
        sum += kernel[k + radius] * white[std::size_t(v) * width + u + k];
        sq += kernel[k + radius] * kernel[k + radius];
      }
      rows[std::size_t(v) * width + u] = sum;
      rows_sq[std::size_t(v) * width + u] = sq;
    }
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      double sum = 0, var = 0;
      for (int k = std::max(-radius, -v); k <= std::min(radius, height - 1 - v); ++k) {
        const std::size_t j = std::size_t(v + k) * width + u;
        sum += kernel[k + radius] * rows[j];
        var += kernel[k + radius] * kernel[k + radius] * rows_sq[j];
      }
      out[std::size_t(v) * width + u] = sum / std::sqrt(var);
    }
  return out;
}

}  // namespace

KinectOptions kinect_for_scene(const Scene& scene, std::uint64_t seed,
                               const SensorPlacement& placement) {
  Rng rng(mix_seed(seed, kKinectStream - 1));
  KinectOptions options;
  const double front = -0.5 * scene.table_size.y();
  options.position =
      Vec3d(rng.uniform(-0.08, 0.08), front - rng.uniform(0.4, 0.5), rng.uniform(0.65, 0.8));
  options.target = Vec3d(rng.uniform(-0.05, 0.05), rng.uniform(0.0, 0.08), 0.0);
  options.position =
      detail::place_sensor(options.position, front, placement.range_scale, placement.elevation_deg);
  return options;
}

PointCloud scan_kinect(const Scene& scene, const KinectOptions& options, double label_radius,
                       std::uint64_t seed) {
  const Eigen::Matrix3d rotation = detail::camera_rotation(options.target - options.position);
  const double focal = options.focal_px * options.width / 640.0;
  const double cx = 0.5 * (options.width - 1), cy = 0.5 * (options.height - 1);
  // Depth from disparity: z = focal * baseline / d, d quantised to 1/subpixel pixel of the IR
  // camera.
  const double focal_baseline =
      options.disparity_focal_px * options.width / 640.0 * options.baseline;
  const Vec3d projector = options.position + options.baseline * rotation.col(0);
  const double min_cos_incidence = std::cos(options.max_incidence_deg * kDeg);
  const std::size_t pixels = std::size_t(options.width) * options.height;

  if (!(options.independent_noise_share >= 0 && options.independent_noise_share <= 1))
    throw std::invalid_argument("kinect: independent_noise_share must be in [0, 1]");
  if (!(options.noise_correlation_px >= 0))
    throw std::invalid_argument("kinect: noise_correlation_px must be >= 0");
  // The depth error: a white share and a spatially correlated share of one unit variance.
  const bool correlated = options.noise_correlation_px > 0 && options.independent_noise_share < 1;
  const std::vector<double> field =
      correlated
          ? correlated_field(options.width, options.height, options.noise_correlation_px, seed)
          : std::vector<double>{};
  const double white_weight = correlated ? std::sqrt(options.independent_noise_share) : 1.0;
  const double field_weight = correlated ? std::sqrt(1.0 - options.independent_noise_share) : 0.0;

  std::vector<detail::Return> returns(pixels);
  primlabel::detail::parallel_for(
      options.height, 0, primlabel::detail::Schedule::Dynamic(8), [&](std::ptrdiff_t v) {
        for (int u = 0; u < options.width; ++u) {
          const std::size_t pixel = std::size_t(v) * options.width + u;
          const Vec3d camera_ray((u - cx) / focal, (v - cy) / focal, 1.0);  // z = 1: depth units
          const Ray ray{options.position, (rotation * camera_ray).normalized()};
          Rng rng(mix_seed(seed, kKinectStream, pixel));
          const double lost = rng.uniform();
          const double noise =
              white_weight * rng.normal() + (correlated ? field_weight * field[pixel] : 0.0);

          const auto hit = scene.cast(ray, 1e-6, options.max_range * 2.0);
          if (!hit || lost < options.dropout) continue;
          if (-ray.dir.dot(hit->normal) < min_cos_incidence) continue;
          const Vec3d point = ray.at(hit->t);
          const double depth = hit->t / camera_ray.norm();
          if (depth < options.min_range || depth > options.max_range) continue;
          if (options.projector_shadow && scene.occluded(projector, point)) continue;

          double measured = depth + options.depth_noise * depth * depth * noise;
          if (options.quantize) {
            const double disparity = focal_baseline / measured;
            measured =
                focal_baseline / (std::round(disparity * options.subpixel) / options.subpixel);
          }
          const Vec3d measured_point = options.position + rotation * (camera_ray * measured);
          returns[pixel] = detail::make_return(scene, *hit, point, measured_point, label_radius);
        }
      });

  PointCloud cloud;
  detail::label_unseen_creases_as_surface(returns, label_radius);
  detail::store_returns(returns, cloud);
  cloud.width = static_cast<std::uint32_t>(options.width);
  cloud.height = static_cast<std::uint32_t>(options.height);
  cloud.viewpoint.origin = options.position.cast<float>();
  cloud.viewpoint.orientation = Eigen::Quaternionf(rotation.cast<float>());
  return cloud;
}

}  // namespace primlabel::synth
