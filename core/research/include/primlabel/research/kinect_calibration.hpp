#pragma once
// Calibration of the simulated Kinect (synth/scanners.hpp) against real organised depth frames:
// the table plane of each frame is fitted robustly (MSAC, then least squares), and per depth bin
// the table points give
// - the residual spread along the viewing ray (depth residual to the plane, 1.4826 * MAD), both to
//   the frame's plane and to a plane per 24x24-pixel tile (the tile removes the table's own
//   unevenness and the sensor's low-frequency depth bias, which the simulator does not model),
// - the disparity quantisation: the spacing of the distinct depth levels (pooled over frames),
//   which for z = F / d with d quantised to 1/subpixel px is z^2 / F, F = focal*baseline*subpixel,
// - the return density: distance between horizontally adjacent table pixels (against z / focal),
// - the missing-return share inside the table's span of each row (isolated holes counted apart:
//   those are random dropouts, the rest mostly projector shadows).
// The fit: F from the level spacing in 1/z (constant, 1/F, for a disparity quantiser), and the
// noise coefficient c of sigma = c * z^2 from the per-bin spreads with the quantisation removed
// (a uniform error of the bin's level spacing convolved with the Gaussian, inverted exactly).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::research {

struct KinectCalibrationOptions {
  double min_depth = 0.5, max_depth = 2.0;  // depth range of the bins (m)
  double bin_width = 0.1;                   // m of depth
  std::size_t min_bin_points = 500;         // bins with fewer table points are not fitted
  float plane_threshold = 0.01f;            // MSAC inlier band (m)
  double max_residual = 0.05;               // points farther from the plane are no table (m)
  int tile_px = 24;                         // tile of the local planes
  std::size_t min_tile_points = 200;        // fewer table points: the tile is not used
  // Levels below this spacing are merged by a depth resolution of the file (mOSD stores mm), so
  // F is fitted only where the spacing is at least this many times the file's resolution.
  double min_level_resolution_ratio = 2.0;
  std::uint64_t seed = 1;
};

struct KinectRangeBin {
  double depth_lo = 0, depth_hi = 0, depth_mean = 0;  // m
  std::uint64_t points = 0;                           // table points in the bin
  double global_spread = NAN;           // robust std of the depth residual to the frame's plane (m)
  double local_spread = NAN;            // ... to the tile's plane (m)
  double level_spacing = NAN;           // mean spacing of the distinct depth levels in the bin (m)
  double point_spacing = NAN;           // median distance between horizontally adjacent pixels (m)
  double point_spacing_ratio = NAN;     // point_spacing / (z / focal): 1 at normal incidence
  double missing_share = NAN;           // missing returns in the table's row spans
  double isolated_missing_share = NAN;  // ... holes whose 4 neighbours all returned
  double local_noise = NAN;             // local_spread with the quantisation removed: sigma (m)
  double global_noise = NAN;            // global_spread with the quantisation removed
  double model_noise = NAN;             // c * z^2 of the fit
  double model_level_spacing = NAN;     // z^2 / F of the fit
};

struct KinectFrameCalibration {
  std::string source;
  std::uint64_t table_points = 0;                   // finite table points given
  std::uint64_t plane_points = 0;                   // within max_residual of the fitted plane
  Eigen::Vector4f plane = Eigen::Vector4f::Zero();  // camera frame
  double tilt_deg = 0;  // angle between the viewing axis and the plane normal
  double depth_min = 0, depth_max = 0;
  double focal_px = NAN;  // from the pixel grid: (u - cx) / (x / z), median
  double global_spread = NAN, local_spread = NAN;  // over the whole frame (m)
  double missing_share = NAN;
};

struct KinectCalibration {
  std::vector<KinectFrameCalibration> frames;
  std::vector<KinectRangeBin> bins;
  double focal_px = NAN;        // median over the frames
  double depth_resolution = 0;  // smallest step between distinct depths in the files (m)
  // Quantisation: F = focal * baseline * subpixel (m px), level spacing = z^2 / F.
  double focal_baseline_subpixel = NAN;
  double quantization_rms_relative = NAN;  // rms of (spacing - z^2 / F) / (z^2 / F) over bins
  std::uint64_t quantization_levels = 0;   // level pairs the fit used
  // Noise: sigma = depth_noise * z^2 from the local spreads (global: from the frames' planes).
  double depth_noise = NAN, global_depth_noise = NAN;
  double noise_rms_relative = NAN;  // rms relative residual of the local fit over the bins
  double noise_exponent = NAN;      // p of a free fit sigma = a * z^p (2 for the model)
  double missing_share = NAN, isolated_missing_share = NAN;  // over all table spans
  // Autocorrelation of the tile residuals of pixels `lag` apart along a row (lags 1, 2, 4, 8,
  // 16): 1 - E[(r_i - r_i+lag)^2] / (2 E[r^2]). Near 0 for independent errors larger than the
  // level spacing; near 1 when neighbours share their error (a disparity is matched over a window
  // of pixels; or errors far below the level spacing, where neighbours share a level).
  std::vector<int> lags;
  std::vector<double> autocorrelation;
};

// Accumulates frames (one at a time: a frame's residuals are kept, its cloud is not).
class KinectCalibrator {
 public:
  explicit KinectCalibrator(KinectCalibrationOptions options = {});
  // `is_table[i]` marks the table points of the organised `cloud` (points in any frame: they are
  // taken into the sensor frame through the cloud's VIEWPOINT). Returns the frame's figures;
  // throws std::invalid_argument for an unorganised cloud, std::runtime_error when no plane fits.
  const KinectFrameCalibration& add_frame(const PointCloud& cloud,
                                          const std::vector<bool>& is_table, std::string source);
  KinectCalibration finish() const;

 private:
  struct Sample {
    float depth, global_residual, local_residual;
  };
  KinectCalibrationOptions options_;
  std::vector<KinectFrameCalibration> frames_;
  std::vector<Sample> samples_;
  struct LevelRun {  // the distinct table depths of one frame in one bin
    int bin;
    std::uint64_t count;
    double first, last;
  };
  std::vector<LevelRun> level_runs_;
  struct BinCounts {
    std::uint64_t span = 0, missing = 0, isolated = 0;
    std::vector<float> spacing, spacing_ratio;
  };
  std::vector<BinCounts> bins_;
  double resolution_ = 0;
  std::vector<double> lag_difference_sq_, lag_square_;  // per lag, for the autocorrelation
};

// 1.4826 * MAD of sigma * N(0, 1) + q * U(-1/2, 1/2): what a robust spread measures when a
// Gaussian error is quantised with step q (the depth uniformly placed against the levels).
double quantized_robust_spread(double sigma, double q);
// The sigma whose quantized_robust_spread is `spread` (0 when the quantisation alone explains it).
double noise_from_quantized_spread(double spread, double q);

// The simulator's correlated depth error fitted to a real calibration by simulation: bare-table
// frames are simulated over a grid of correlation lengths and white shares and calibrated like the
// real ones; the grid point whose autocorrelation at 1, 2 and 4 px is closest to the real one
// wins, and the noise coefficient is scaled so that the simulated tile noise matches the real
// (tiles absorb part of a correlated error, so the simulator's coefficient is larger).
struct KinectSimulationFit {
  double noise_correlation_px = 0, independent_noise_share = 1;
  double depth_noise = NAN;          // the simulator's coefficient
  double autocorrelation_rms = NAN;  // over lags 1, 2, 4 px, real against simulated
  KinectCalibration simulated;       // calibration of frames simulated with the fitted values
};
KinectSimulationFit fit_kinect_simulation(
    const KinectCalibration& real, const std::function<void(const std::string&)>& progress = {});

// Every mOSD scene (label 1-9 the table) in `files`, through a calibrator.
KinectCalibration calibrate_mosd(const std::vector<std::string>& files,
                                 const KinectCalibrationOptions& options = {},
                                 const std::function<void(const std::string&)>& progress = {});

std::string kinect_calibration_text(const KinectCalibration& calibration);
std::string kinect_calibration_json(const KinectCalibration& calibration);
std::string kinect_simulation_fit_text(const KinectSimulationFit& fit);

}  // namespace primlabel::research
