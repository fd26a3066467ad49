// The Kinect calibration (research/kinect_calibration.hpp): the quantised-spread model, recovery
// of known noise and quantisation from simulated frames, and plausible figures on a real mOSD
// scene (../shared/data/mosd; skipped when absent).

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "primlabel/research/kinect_calibration.hpp"
#include "primlabel/synth/scanners.hpp"

namespace primlabel::research {
namespace {

TEST(KinectCalibration, QuantizedSpreadMatchesSampledErrors) {
  EXPECT_DOUBLE_EQ(quantized_robust_spread(2e-3, 0), 2e-3);
  EXPECT_NEAR(quantized_robust_spread(0, 4e-3), 1.4826e-3, 1e-9);  // MAD of a uniform: q / 4
  // Against the robust spread of sampled sigma N + q U, over noise below and above the step.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> uniform(-0.5, 0.5);
  const double q = 3e-3;
  for (double sigma : {0.3e-3, 1e-3, 3e-3}) {
    std::vector<double> x(200000);
    for (double& v : x) v = sigma * gauss(rng) + q * uniform(rng);
    for (double& v : x) v = std::abs(v);
    std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
    const double sampled = 1.4826 * x[x.size() / 2];
    EXPECT_NEAR(quantized_robust_spread(sigma, q), sampled, 0.01 * sampled) << sigma;
    EXPECT_NEAR(noise_from_quantized_spread(quantized_robust_spread(sigma, q), q), sigma,
                1e-3 * sigma);
  }
  EXPECT_EQ(noise_from_quantized_spread(0.5e-3, q), 0.0);  // below the quantisation alone
}

// A bare-table Kinect frame with known noise and quantisation, calibrated on its table.
KinectCalibration calibrate_synthetic(double depth_noise, double disparity_focal_px,
                                      std::uint64_t seed, double correlation_px = 0) {
  const synth::Scene scene = synth::make_scene(synth::SceneKind::kEmptyTable, seed);
  synth::KinectOptions options = synth::kinect_for_scene(scene, seed);
  options.depth_noise = depth_noise;
  options.disparity_focal_px = disparity_focal_px;
  options.noise_correlation_px = correlation_px;
  options.independent_noise_share = correlation_px > 0 ? 0.05 : 1.0;
  const PointCloud cloud = synth::scan_kinect(scene, options, 0.025, seed);
  std::vector<bool> table(cloud.size());
  const FloatField* object = cloud.find_field("object");
  // The table's top face (the slab's front face, at y = front, belongs to object 0 too).
  const float front = static_cast<float>(-0.5 * scene.table_size.y() + 0.01);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    table[i] = object->values[i] == 0.0f && cloud.xyz[i].y() > front;
  KinectCalibrator calibrator;
  calibrator.add_frame(cloud, table, "synthetic");
  return calibrator.finish();
}
TEST(KinectCalibration, RecoversKnownNoiseAndQuantisation) {
  // Noise well below the step (quantisation dominates the spread) and well above it.
  for (const auto [noise, ir_focal] : {std::pair{0.8e-3, 560.0}, std::pair{3.0e-3, 610.0}}) {
    const KinectCalibration c = calibrate_synthetic(noise, ir_focal, 11);
    const double F = ir_focal * 0.075 * 8;
    EXPECT_NEAR(c.focal_px, 525.0, 0.05);
    EXPECT_NEAR(c.focal_baseline_subpixel, F, 0.01 * F) << noise;
    EXPECT_LT(c.quantization_rms_relative, 0.03);
    EXPECT_NEAR(c.depth_noise, noise, 0.08 * noise) << "F " << F;
    EXPECT_NEAR(c.global_depth_noise, noise, 0.08 * noise);  // a flat table: no local bias
    EXPECT_NEAR(c.noise_exponent, 2.0, 0.25);
    EXPECT_LT(c.isolated_missing_share, 1e-3);  // no dropout simulated
    // The simulator draws every pixel's error on its own.
    ASSERT_EQ(c.autocorrelation.size(), 5u);
    for (double r : c.autocorrelation) EXPECT_NEAR(r, 0.0, 0.1);
    std::size_t fitted = 0;
    for (const auto& bin : c.bins) fitted += std::isfinite(bin.model_noise);
    EXPECT_GE(fitted, 6u);
  }
}

// The simulator's correlated error (its defaults: 3.5 px, 5% white): the frame's plane still sees
// the whole error, tiles a part of it, and neighbours share most of theirs.
TEST(KinectCalibration, MeasuresTheCorrelatedError) {
  const KinectCalibration c = calibrate_synthetic(2.25e-3, 575, 11, 3.5);
  EXPECT_NEAR(c.global_depth_noise, 2.25e-3, 0.08 * 2.25e-3);
  EXPECT_LT(c.depth_noise, 0.85 * c.global_depth_noise);
  EXPECT_NEAR(c.depth_noise, 1.70e-3, 0.1 * 1.70e-3);  // the real frames' tile noise
  ASSERT_EQ(c.lags.size(), 5u);
  EXPECT_EQ(c.lags[2], 4);
  EXPECT_NEAR(c.autocorrelation[0], 0.70, 0.1);  // the real frames: 0.70, 0.55, 0.34
  EXPECT_NEAR(c.autocorrelation[2], 0.34, 0.1);
  EXPECT_LT(c.autocorrelation[3], 0.15);
}

TEST(KinectCalibration, RealMosdSceneIsPlausible) {
  const std::string path = std::string(PRIMLABEL_SHARED_DATA) + "/mosd/learn0.pcd";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const KinectCalibration c = calibrate_mosd({path});
  ASSERT_EQ(c.frames.size(), 1u);
  EXPECT_GT(c.frames[0].plane_points, 100000u);  // learn0: 153,323 table points
  EXPECT_NEAR(c.focal_px, 525.0, 5.0);
  EXPECT_NEAR(c.depth_resolution, 1e-3, 1e-5);  // mOSD stores millimetres
  // Kinect: 1/8 px disparity, 7.5 cm baseline, IR focal ~580 px: F ~ 350 m px.
  EXPECT_GT(c.focal_baseline_subpixel, 300.0);
  EXPECT_LT(c.focal_baseline_subpixel, 400.0);
  EXPECT_GT(c.depth_noise, 0.5e-3);
  EXPECT_LT(c.depth_noise, 4e-3);
  EXPECT_GE(c.global_depth_noise, c.depth_noise);  // the frame's plane adds the low frequencies
  EXPECT_LT(c.missing_share, 0.1);
  // Unlike the simulator's, the real errors of nearby pixels are correlated (45 scenes: 0.70 at
  // 1 px, 0.34 at 4 px, 0.06 at 8 px).
  EXPECT_GT(c.autocorrelation[0], 0.5);
  EXPECT_LT(c.autocorrelation[3], c.autocorrelation[0]);
}

TEST(KinectCalibration, RejectsUnorganisedClouds) {
  PointCloud cloud;
  cloud.resize_unorganized(10);
  KinectCalibrator calibrator;
  EXPECT_THROW(calibrator.add_frame(cloud, std::vector<bool>(10, true), "x"),
               std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::research
