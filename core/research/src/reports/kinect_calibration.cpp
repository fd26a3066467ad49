// Kinect calibration from the table planes of real organised depth frames.

#include "primlabel/research/kinect_calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/research/mosd_report.hpp"
#include "primlabel/synth/scanners.hpp"
#include "primlabel/synth/scene.hpp"
#include "primlabel/tabletop/plane_fit.hpp"

namespace primlabel::research {
namespace {

constexpr double kMadToSigma = 1.4826;
// Depths closer than this are one level: float round-off of the transform into the sensor frame.
constexpr double kSameLevel = 1e-5;
constexpr std::array<int, 5> kLags = {1, 2, 4, 8, 16};

std::string format(const char* fmt, auto... args) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, fmt, args...);
  return buffer;
}

double median(std::vector<float> values) {
  if (values.empty()) return NAN;
  const auto mid = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

// 1.4826 * median absolute deviation from the median.
double robust_spread(std::vector<float> values) {
  if (values.size() < 2) return NAN;
  const double m = median(values);
  for (float& v : values) v = static_cast<float>(std::abs(v - m));
  return kMadToSigma * median(std::move(values));
}

double normal_cdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// Depth of the plane n.p + d = 0 along the ray through (rx, ry, 1).
double plane_depth(const Eigen::Vector4f& plane, double rx, double ry) {
  const double denom = plane[0] * rx + plane[1] * ry + plane[2];
  return std::abs(denom) < 1e-9 ? NAN : -plane[3] / denom;
}

// Least-squares line value = slope * x + intercept.
struct Line {
  double slope = NAN, intercept = NAN;
};
Line fit_line(const std::vector<std::pair<double, double>>& xy) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (auto [x, y] : xy) sx += x, sy += y, sxx += x * x, sxy += x * y;
  const double n = double(xy.size()), det = n * sxx - sx * sx;
  if (xy.size() < 2 || std::abs(det) < 1e-12) return {};
  Line line;
  line.slope = (n * sxy - sx * sy) / det;
  line.intercept = (sy - line.slope * sx) / n;
  return line;
}

}  // namespace

double quantized_robust_spread(double sigma, double q) {
  if (!(q > 0)) return sigma;
  if (!(sigma > 0)) return kMadToSigma * q / 4.0;
  // P(|X| <= m) for X = sigma N + q U, U on (-1/2, 1/2): the Gaussian CDF averaged over the
  // uniform offset (midpoint rule; smooth integrand).
  constexpr int kNodes = 256;
  auto inside = [&](double m) {
    double sum = 0;
    for (int k = 0; k < kNodes; ++k) {
      const double u = q * ((k + 0.5) / kNodes - 0.5);
      sum += normal_cdf((m - u) / sigma) - normal_cdf((-m - u) / sigma);
    }
    return sum / kNodes;
  };
  double lo = 0, hi = 5 * sigma + q;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (inside(mid) < 0.5 ? lo : hi) = mid;
  }
  return kMadToSigma * 0.5 * (lo + hi);
}

double noise_from_quantized_spread(double spread, double q) {
  if (!std::isfinite(spread)) return NAN;
  if (spread <= quantized_robust_spread(0, q)) return 0;
  double lo = 0, hi = spread;  // adding the uniform error only widens: sigma <= spread
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (quantized_robust_spread(mid, q) < spread ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

KinectCalibrator::KinectCalibrator(KinectCalibrationOptions options) : options_(options) {
  if (!(options_.bin_width > 0) || !(options_.max_depth > options_.min_depth) ||
      !(options_.min_depth > 0))
    throw std::invalid_argument("calibration bins: need 0 < min_depth < max_depth, bin_width > 0");
  if (options_.tile_px < 4) throw std::invalid_argument("calibration tiles: tile_px >= 4");
  const int count =
      static_cast<int>(std::ceil((options_.max_depth - options_.min_depth) / options_.bin_width));
  bins_.resize(static_cast<std::size_t>(count));
  lag_difference_sq_.assign(kLags.size(), 0.0);
  lag_square_.assign(kLags.size(), 0.0);
}

const KinectFrameCalibration& KinectCalibrator::add_frame(const PointCloud& cloud,
                                                          const std::vector<bool>& is_table,
                                                          std::string source) {
  if (!cloud.organized()) throw std::invalid_argument(source + ": not an organised depth frame");
  if (is_table.size() != cloud.size())
    throw std::invalid_argument(source + ": the table mask does not match the cloud");
  const int width = static_cast<int>(cloud.width), height = static_cast<int>(cloud.height);
  const Eigen::Matrix3f to_sensor = cloud.viewpoint.orientation.toRotationMatrix().transpose();

  // Points in the sensor frame (z the depth), and the table points among them.
  std::vector<Vec3f> points(cloud.size(), Vec3f::Constant(NAN));
  std::vector<std::uint32_t> table;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.xyz[i].allFinite()) continue;
    points[i] = to_sensor * (cloud.xyz[i] - cloud.viewpoint.origin);
    if (is_table[i] && points[i].z() > 0) table.push_back(static_cast<std::uint32_t>(i));
  }
  KinectFrameCalibration frame;
  frame.source = std::move(source);
  frame.table_points = table.size();

  tabletop::PlaneFitOptions fit_options;
  fit_options.distance_threshold = options_.plane_threshold;
  fit_options.seed = options_.seed;
  const tabletop::PlaneFit fit = tabletop::fit_plane(points, table, fit_options);
  if (fit.status != tabletop::PlaneFitStatus::kOk)
    throw std::runtime_error(frame.source + ": no table plane (" + fit.message + ")");
  frame.plane = fit.plane;
  frame.tilt_deg = std::acos(std::min(1.0f, std::abs(fit.plane[2]))) * 180.0 / M_PI;

  // The pixel grid from the points: u = fx * x / z + cx (as v): rays of missing pixels too.
  std::vector<std::pair<double, double>> ux, vy;
  for (std::uint32_t i : table) {
    const Vec3f& p = points[i];
    ux.emplace_back(p.x() / p.z(), double(i % width));
    vy.emplace_back(p.y() / p.z(), double(i / width));
  }
  const Line grid_u = fit_line(ux), grid_v = fit_line(vy);
  frame.focal_px = 0.5 * (grid_u.slope + grid_v.slope);
  auto ray = [&](int u, int v) {
    return std::pair((u - grid_u.intercept) / grid_u.slope, (v - grid_v.intercept) / grid_v.slope);
  };

  // Residuals to the frame's plane; the table is what lies within max_residual of it.
  std::vector<float> global(cloud.size(), NAN), depth_of(cloud.size(), NAN);
  std::vector<std::uint32_t> plane_points;
  for (std::uint32_t i : table) {
    const Vec3f& p = points[i];
    const double z = plane_depth(fit.plane, p.x() / p.z(), p.y() / p.z());
    const double r = p.z() - z;
    if (!(std::abs(r) < options_.max_residual)) continue;
    global[i] = static_cast<float>(r);
    depth_of[i] = static_cast<float>(z);
    plane_points.push_back(i);
  }
  frame.plane_points = plane_points.size();

  // Residuals to each tile's own least-squares plane, refitted once without its outliers.
  std::vector<float> local(cloud.size(), NAN);
  const int tile = options_.tile_px;
  for (int v0 = 0; v0 < height; v0 += tile)
    for (int u0 = 0; u0 < width; u0 += tile) {
      std::vector<std::uint32_t> members;
      for (int v = v0; v < std::min(v0 + tile, height); ++v)
        for (int u = u0; u < std::min(u0 + tile, width); ++u) {
          const std::size_t i = std::size_t(v) * width + u;
          if (std::isfinite(global[i])) members.push_back(static_cast<std::uint32_t>(i));
        }
      if (members.size() < options_.min_tile_points) continue;
      auto residuals = [&](const Eigen::Vector4f& plane) {
        std::vector<float> out;
        for (std::uint32_t i : members) {
          const Vec3f& p = points[i];
          out.push_back(
              static_cast<float>(p.z() - plane_depth(plane, p.x() / p.z(), p.y() / p.z())));
        }
        return out;
      };
      Eigen::Vector4f plane = tabletop::estimate_plane(points, members).plane;
      std::vector<float> r = residuals(plane);
      const double band = 4.0 * robust_spread(r);
      std::vector<std::uint32_t> kept;
      for (std::size_t k = 0; k < members.size(); ++k)
        if (std::abs(r[k]) <= band) kept.push_back(members[k]);
      if (kept.size() < options_.min_tile_points) continue;
      plane = tabletop::estimate_plane(points, kept).plane;
      if (!plane.allFinite()) continue;
      r = residuals(plane);
      for (std::size_t k = 0; k < members.size(); ++k) local[members[k]] = r[k];
    }

  auto bin_of = [&](double z) -> int {
    if (!(z >= options_.min_depth && z < options_.max_depth)) return -1;
    return std::min(static_cast<int>((z - options_.min_depth) / options_.bin_width),
                    static_cast<int>(bins_.size()) - 1);
  };

  std::vector<float> frame_global, frame_local;
  std::vector<std::vector<float>> levels(bins_.size());
  frame.depth_min = INFINITY, frame.depth_max = -INFINITY;
  for (std::uint32_t i : plane_points) {
    const double z = depth_of[i];
    frame.depth_min = std::min(frame.depth_min, z), frame.depth_max = std::max(frame.depth_max, z);
    frame_global.push_back(global[i]);
    if (std::isfinite(local[i])) frame_local.push_back(local[i]);
    const int b = bin_of(z);
    if (b < 0) continue;
    samples_.push_back({static_cast<float>(z), global[i], local[i]});
    levels[b].push_back(points[i].z());
    // Return density: the next pixel of the row, when it is table too.
    const int u = static_cast<int>(i % width);
    if (u + 1 < width && std::isfinite(global[i + 1])) {
      const double spacing = (points[i + 1] - points[i]).norm();
      bins_[b].spacing.push_back(static_cast<float>(spacing));
      bins_[b].spacing_ratio.push_back(static_cast<float>(spacing * frame.focal_px / z));
    }
  }
  // Pairs of tile residuals `lag` pixels apart along a row; outliers beyond the MSAC band skipped.
  for (std::size_t k = 0; k < kLags.size(); ++k)
    for (std::uint32_t i : plane_points) {
      const int u = static_cast<int>(i % width);
      if (u + kLags[k] >= width) continue;
      const float a = local[i], b = local[i + kLags[k]];
      if (!(std::abs(a) < options_.plane_threshold && std::abs(b) < options_.plane_threshold))
        continue;
      lag_difference_sq_[k] += double(a - b) * double(a - b);
      lag_square_[k] += 0.5 * (double(a) * a + double(b) * b);
    }
  frame.global_spread = robust_spread(std::move(frame_global));
  frame.local_spread = robust_spread(std::move(frame_local));

  // The distinct depth levels per bin of this frame (frames of different devices may quantise
  // differently, so levels are counted per frame).
  for (std::size_t b = 0; b < levels.size(); ++b) {
    auto& z = levels[b];
    if (z.size() < options_.min_bin_points) continue;
    std::sort(z.begin(), z.end());
    std::vector<double> distinct{z.front()};
    for (float value : z)
      if (value - distinct.back() > kSameLevel) distinct.push_back(value);
    if (distinct.size() < 3) continue;
    for (std::size_t k = 1; k < distinct.size(); ++k) {
      const double gap = distinct[k] - distinct[k - 1];
      if (resolution_ == 0 || gap < resolution_) resolution_ = gap;
    }
    level_runs_.push_back({static_cast<int>(b), static_cast<std::uint64_t>(distinct.size()),
                           distinct.front(), distinct.back()});
  }

  // Missing returns inside each row's table span (object pixels are returns of another surface).
  std::uint64_t span = 0, missing = 0;
  for (int v = 0; v < height; ++v) {
    int first = -1, last = -1;
    for (int u = 0; u < width; ++u)
      if (std::isfinite(global[std::size_t(v) * width + u])) (first < 0 ? first : last) = u;
    if (first < 0 || last < 0) continue;
    for (int u = first; u <= last; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      const bool returned = points[i].allFinite();
      if (returned && !std::isfinite(global[i])) continue;  // an object, or off the plane
      const auto [rx, ry] = ray(u, v);
      const int b = bin_of(plane_depth(fit.plane, rx, ry));
      ++span;
      if (b >= 0) ++bins_[b].span;
      if (returned) continue;
      ++missing;
      if (b < 0) continue;
      ++bins_[b].missing;
      auto table_at = [&](int uu, int vv) {
        return uu >= 0 && vv >= 0 && uu < width && vv < height &&
               std::isfinite(global[std::size_t(vv) * width + uu]);
      };
      if (table_at(u - 1, v) && table_at(u + 1, v) && table_at(u, v - 1) && table_at(u, v + 1))
        ++bins_[b].isolated;
    }
  }
  frame.missing_share = span ? double(missing) / double(span) : NAN;
  frames_.push_back(std::move(frame));
  return frames_.back();
}

KinectCalibration KinectCalibrator::finish() const {
  KinectCalibration out;
  out.frames = frames_;
  std::vector<float> focals;
  for (const auto& f : frames_) focals.push_back(static_cast<float>(f.focal_px));
  out.focal_px = median(focals);
  out.depth_resolution = resolution_;

  // F: levels are equally spaced in 1/z by 1/F; pooled over frame bins whose spacing is well
  // above the resolution of the files (rounding merges finer levels).
  double level_steps = 0, inverse_span = 0;
  std::vector<double> bin_steps(bins_.size(), 0), bin_inverse(bins_.size(), 0);
  for (const LevelRun& run : level_runs_) {
    const double spacing = (run.last - run.first) / double(run.count - 1);
    bin_steps[run.bin] += double(run.count - 1);
    bin_inverse[run.bin] += 1.0 / run.first - 1.0 / run.last;
    if (spacing < options_.min_level_resolution_ratio * resolution_) continue;
    level_steps += double(run.count - 1);
    inverse_span += 1.0 / run.first - 1.0 / run.last;
  }
  out.quantization_levels = static_cast<std::uint64_t>(level_steps);
  if (inverse_span > 0) out.focal_baseline_subpixel = level_steps / inverse_span;
  const double F = out.focal_baseline_subpixel;

  std::vector<std::vector<Sample>> by_bin(bins_.size());
  for (const Sample& s : samples_) {
    const int b = std::min(static_cast<int>((s.depth - options_.min_depth) / options_.bin_width),
                           static_cast<int>(bins_.size()) - 1);
    if (b >= 0) by_bin[b].push_back(s);
  }
  std::uint64_t span = 0, missing = 0, isolated = 0;
  double quant_sq = 0, quant_n = 0;
  for (std::size_t b = 0; b < bins_.size(); ++b) {
    KinectRangeBin bin;
    bin.depth_lo = options_.min_depth + double(b) * options_.bin_width;
    bin.depth_hi = std::min(options_.max_depth, bin.depth_lo + options_.bin_width);
    const auto& s = by_bin[b];
    bin.points = s.size();
    span += bins_[b].span, missing += bins_[b].missing, isolated += bins_[b].isolated;
    if (bins_[b].span) {
      bin.missing_share = double(bins_[b].missing) / double(bins_[b].span);
      bin.isolated_missing_share = double(bins_[b].isolated) / double(bins_[b].span);
    }
    if (s.size() < options_.min_bin_points) {
      out.bins.push_back(bin);
      continue;
    }
    double sum = 0;
    std::vector<float> g, l;
    for (const Sample& x : s) {
      sum += x.depth;
      g.push_back(x.global_residual);
      if (std::isfinite(x.local_residual)) l.push_back(x.local_residual);
    }
    bin.depth_mean = sum / double(s.size());
    bin.global_spread = robust_spread(std::move(g));
    bin.local_spread = robust_spread(std::move(l));
    bin.point_spacing = median(bins_[b].spacing);
    bin.point_spacing_ratio = median(bins_[b].spacing_ratio);
    const double z = bin.depth_mean;
    // The bin's own F (its level steps over their span in 1/z) gives its mean level spacing.
    if (bin_inverse[b] > 0) bin.level_spacing = z * z * bin_inverse[b] / bin_steps[b];
    if (F > 0) bin.model_level_spacing = z * z / F;
    const double q = F > 0 ? z * z / F : (std::isfinite(bin.level_spacing) ? bin.level_spacing : 0);
    bin.local_noise = noise_from_quantized_spread(bin.local_spread, q);
    bin.global_noise = noise_from_quantized_spread(bin.global_spread, q);
    out.bins.push_back(bin);
  }
  if (span) {
    out.missing_share = double(missing) / double(span);
    out.isolated_missing_share = double(isolated) / double(span);
  }

  // sigma = c z^2 by weighted least squares (weights: points), and a free exponent in log-log.
  auto fit_coefficient = [&](auto noise_of) {
    double num = 0, den = 0;
    for (const auto& bin : out.bins) {
      const double sigma = noise_of(bin), z = bin.depth_mean;
      if (!std::isfinite(sigma) || bin.points < options_.min_bin_points) continue;
      num += double(bin.points) * sigma * z * z;
      den += double(bin.points) * z * z * z * z;
    }
    return den > 0 ? num / den : NAN;
  };
  out.depth_noise = fit_coefficient([](const KinectRangeBin& b) { return b.local_noise; });
  out.global_depth_noise = fit_coefficient([](const KinectRangeBin& b) { return b.global_noise; });
  double rel_sq = 0, weight = 0;
  std::vector<std::pair<double, double>> log_log;
  for (auto& bin : out.bins) {
    if (bin.points < options_.min_bin_points || !std::isfinite(bin.local_noise)) continue;
    const double z = bin.depth_mean;
    bin.model_noise = out.depth_noise * z * z;
    const double rel = (bin.local_noise - bin.model_noise) / bin.model_noise;
    rel_sq += double(bin.points) * rel * rel, weight += double(bin.points);
    if (bin.local_noise > 0) log_log.emplace_back(std::log(z), std::log(bin.local_noise));
    if (std::isfinite(bin.level_spacing) && std::isfinite(bin.model_level_spacing) &&
        bin.level_spacing >= options_.min_level_resolution_ratio * resolution_) {
      const double qrel = (bin.level_spacing - bin.model_level_spacing) / bin.model_level_spacing;
      quant_sq += qrel * qrel, quant_n += 1;
    }
  }
  if (weight > 0) out.noise_rms_relative = std::sqrt(rel_sq / weight);
  for (std::size_t k = 0; k < kLags.size(); ++k) {
    out.lags.push_back(kLags[k]);
    out.autocorrelation.push_back(
        lag_square_[k] > 0 ? 1.0 - lag_difference_sq_[k] / (2.0 * lag_square_[k]) : NAN);
  }
  if (quant_n > 0) out.quantization_rms_relative = std::sqrt(quant_sq / quant_n);
  out.noise_exponent = fit_line(log_log).slope;
  return out;
}

namespace {

// Bare-table frames (seeds 11, 12) simulated with `options`' error model, calibrated on the
// table's top face.
KinectCalibration calibrate_simulated(double depth_noise, double correlation_px,
                                      double independent_share, int frames) {
  KinectCalibrator calibrator;
  for (int k = 0; k < frames; ++k) {
    const std::uint64_t seed = 11 + static_cast<std::uint64_t>(k);
    const synth::Scene scene = synth::make_scene(synth::SceneKind::kEmptyTable, seed);
    synth::KinectOptions options = synth::kinect_for_scene(scene, seed);
    options.depth_noise = depth_noise;
    options.noise_correlation_px = correlation_px;
    options.independent_noise_share = independent_share;
    const PointCloud cloud = synth::scan_kinect(scene, options, 0.025, seed);
    const FloatField* object = cloud.find_field("object");
    // The top face only: the slab's front face (y = front) belongs to the table object too.
    const float front = static_cast<float>(-0.5 * scene.table_size.y() + 0.01);
    std::vector<bool> table(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
      table[i] = object->values[i] == 0.0f && cloud.xyz[i].y() > front;
    calibrator.add_frame(cloud, table, "simulated:" + std::to_string(seed));
  }
  return calibrator.finish();
}

double autocorrelation_distance(const KinectCalibration& a, const KinectCalibration& b) {
  double sum = 0;
  int n = 0;
  for (std::size_t k = 0; k < std::min(a.lags.size(), b.lags.size()); ++k)
    if (a.lags[k] <= 4) sum += std::pow(a.autocorrelation[k] - b.autocorrelation[k], 2), ++n;
  return n ? std::sqrt(sum / n) : NAN;
}

}  // namespace

KinectSimulationFit fit_kinect_simulation(const KinectCalibration& real,
                                          const std::function<void(const std::string&)>& progress) {
  if (!(real.depth_noise > 0) || real.autocorrelation.empty())
    throw std::invalid_argument("the real calibration has no noise fit to match");
  constexpr double kProbeNoise = 1.7e-3;  // the coefficient the grid is simulated with
  KinectSimulationFit best;
  best.autocorrelation_rms = INFINITY;
  double best_tile_noise = NAN;
  for (double correlation : {0.0, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0})
    for (double share : {0.0, 0.05, 0.1, 0.2, 0.4}) {
      if (correlation == 0 && share > 0) continue;  // all white already
      const KinectCalibration sim = calibrate_simulated(kProbeNoise, correlation, share, 1);
      const double distance = autocorrelation_distance(real, sim);
      if (progress)
        progress(
            format("simulated: correlation %.1f px, white share %.2f: autocorrelation rms "
                   "%.3f, tile noise %.4g for %.4g",
                   correlation, share, distance, sim.depth_noise, kProbeNoise));
      if (distance < best.autocorrelation_rms)
        best.autocorrelation_rms = distance, best.noise_correlation_px = correlation,
        best.independent_noise_share = share, best_tile_noise = sim.depth_noise;
    }
  if (best.noise_correlation_px == 0) best.independent_noise_share = 1;
  best.depth_noise = real.depth_noise * kProbeNoise / best_tile_noise;
  best.simulated = calibrate_simulated(best.depth_noise, best.noise_correlation_px,
                                       best.independent_noise_share, 2);
  best.autocorrelation_rms = autocorrelation_distance(real, best.simulated);
  return best;
}

std::string kinect_simulation_fit_text(const KinectSimulationFit& fit) {
  std::string out = format(
      "simulator fit: depth_noise %.4g, noise_correlation_px %.1f, independent_noise_share %.2f; "
      "its frames calibrate to tile noise %.4g * z^2, frame-plane noise %.4g * z^2, F %.1f,",
      fit.depth_noise, fit.noise_correlation_px, fit.independent_noise_share,
      fit.simulated.depth_noise, fit.simulated.global_depth_noise,
      fit.simulated.focal_baseline_subpixel);
  for (std::size_t k = 0; k < fit.simulated.lags.size(); ++k)
    out += format(" lag %d px %.3f%s", fit.simulated.lags[k], fit.simulated.autocorrelation[k],
                  k + 1 < fit.simulated.lags.size() ? "," : "");
  out += format(" (rms to the real over 1-4 px %.3f)\n", fit.autocorrelation_rms);
  return out;
}

KinectCalibration calibrate_mosd(const std::vector<std::string>& files,
                                 const KinectCalibrationOptions& options,
                                 const std::function<void(const std::string&)>& progress) {
  KinectCalibrator calibrator(options);
  for (const std::string& path : files) {
    const PointCloud cloud = read_cloud(path);
    if (!cloud.has_labels())
      throw std::runtime_error(path + ": no label field (an mOSD scene labels table and objects)");
    std::vector<bool> table(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) table[i] = is_mosd_table_label(cloud.labels[i]);
    const KinectFrameCalibration& f = calibrator.add_frame(cloud, table, path);
    if (progress)
      progress(format(
          "%s: %llu table points, depth %.2f-%.2f m, tilt %.1f deg, spread %.2f mm "
          "(tiles %.2f mm), missing %.2f%%",
          path.c_str(), static_cast<unsigned long long>(f.plane_points), f.depth_min, f.depth_max,
          f.tilt_deg, 1e3 * f.global_spread, 1e3 * f.local_spread, 100 * f.missing_share));
  }
  return calibrator.finish();
}

std::string kinect_calibration_text(const KinectCalibration& c) {
  std::string out = format("%-11s %9s %9s %9s %9s %9s %9s %9s %8s %8s %8s\n", "depth m", "points",
                           "spread mm", "tiles mm", "sigma mm", "model mm", "levels mm", "model mm",
                           "spacing", "missing", "holes");
  for (const auto& b : c.bins) {
    if (!b.points) continue;
    out += format("%4.2f-%4.2f %9llu %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %8.3f %7.2f%% %7.3f%%\n",
                  b.depth_lo, b.depth_hi, static_cast<unsigned long long>(b.points),
                  1e3 * b.global_spread, 1e3 * b.local_spread, 1e3 * b.local_noise,
                  1e3 * b.model_noise, 1e3 * b.level_spacing, 1e3 * b.model_level_spacing,
                  b.point_spacing_ratio, 100 * b.missing_share, 100 * b.isolated_missing_share);
  }
  out += format(
      "frames %zu, focal %.2f px, depth resolution of the files %.3g mm\n"
      "quantisation: focal*baseline*subpixel F = %.1f m px (level spacing z^2/F; %llu level "
      "steps; rms relative residual %.3f)\n"
      "noise: sigma = %.4g * z^2 (tiles; rms relative residual %.3f, free exponent %.2f); "
      "to the frames' planes %.4g * z^2\n"
      "missing returns in the table spans %.2f%%, isolated holes %.3f%%\n",
      c.frames.size(), c.focal_px, 1e3 * c.depth_resolution, c.focal_baseline_subpixel,
      static_cast<unsigned long long>(c.quantization_levels), c.quantization_rms_relative,
      c.depth_noise, c.noise_rms_relative, c.noise_exponent, c.global_depth_noise,
      100 * c.missing_share, 100 * c.isolated_missing_share);
  out += "autocorrelation of the tile residuals along rows:";
  for (std::size_t k = 0; k < c.lags.size(); ++k)
    out += format(" lag %d px %.3f%s", c.lags[k], c.autocorrelation[k],
                  k + 1 < c.lags.size() ? "," : "\n");
  return out;
}

std::string kinect_calibration_json(const KinectCalibration& c) {
  auto num = [](double v) { return json::rounded(v, "%.6g"); };
  json::Json bins = json::Json::array(), frames = json::Json::array();
  for (const auto& b : c.bins)
    bins.push_back({{"depth_lo", num(b.depth_lo)},
                    {"depth_hi", num(b.depth_hi)},
                    {"depth_mean", num(b.depth_mean)},
                    {"points", b.points},
                    {"global_spread", num(b.global_spread)},
                    {"local_spread", num(b.local_spread)},
                    {"local_noise", num(b.local_noise)},
                    {"global_noise", num(b.global_noise)},
                    {"model_noise", num(b.model_noise)},
                    {"level_spacing", num(b.level_spacing)},
                    {"model_level_spacing", num(b.model_level_spacing)},
                    {"point_spacing", num(b.point_spacing)},
                    {"point_spacing_ratio", num(b.point_spacing_ratio)},
                    {"missing_share", num(b.missing_share)},
                    {"isolated_missing_share", num(b.isolated_missing_share)}});
  for (const auto& f : c.frames)
    frames.push_back({{"source", f.source},
                      {"table_points", f.table_points},
                      {"plane_points", f.plane_points},
                      {"tilt_deg", num(f.tilt_deg)},
                      {"depth_min", num(f.depth_min)},
                      {"depth_max", num(f.depth_max)},
                      {"focal_px", num(f.focal_px)},
                      {"global_spread", num(f.global_spread)},
                      {"local_spread", num(f.local_spread)},
                      {"missing_share", num(f.missing_share)}});
  json::Json autocorrelation = json::Json::array();
  for (double r : c.autocorrelation) autocorrelation.push_back(num(r));
  const json::Json root = {{"frames", c.frames.size()},
                           {"focal_px", num(c.focal_px)},
                           {"depth_resolution", num(c.depth_resolution)},
                           {"focal_baseline_subpixel", num(c.focal_baseline_subpixel)},
                           {"quantization_level_steps", c.quantization_levels},
                           {"quantization_rms_relative", num(c.quantization_rms_relative)},
                           {"depth_noise", num(c.depth_noise)},
                           {"noise_rms_relative", num(c.noise_rms_relative)},
                           {"noise_exponent", num(c.noise_exponent)},
                           {"global_depth_noise", num(c.global_depth_noise)},
                           {"missing_share", num(c.missing_share)},
                           {"isolated_missing_share", num(c.isolated_missing_share)},
                           {"lags", c.lags},
                           {"autocorrelation", std::move(autocorrelation)},
                           {"bins", std::move(bins)},
                           {"per_frame", std::move(frames)}};
  return json::dump(root) + "\n";
}

}  // namespace primlabel::research
