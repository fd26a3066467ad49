#pragma once
// Simulated range sensors: rays cast from a sensor pose into a scene (2.5D: the first surface
// along each ray is what the sensor returns, so hidden surfaces give no points), with the noise,
// quantisation and dropouts of the real device. Every ray draws its random numbers from its own
// counter-based stream, so a scan is bit-identical for a seed whatever the thread count.
//
// Output clouds are in the world frame (z up, table top at z = 0) with fields x y z, `label`
// (PrimitiveClass id at the label radius, computed from the noise-free hit), `rgba` (the object's
// colour, shaded) and `object` (0 the table, 1.. the objects, -1 no return), and VIEWPOINT = the
// sensor's pose (origin; orientation whose z axis is the viewing direction).

#include <cstdint>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/synth/scene.hpp"

namespace primlabel::synth {

// SICK LMS400 on a tilting arm, as in Rusu et al. 2009: a fan of rays in a scan plane through the
// sensor's horizontal right axis, swept in pitch across the table. Unorganised output (returns
// only).
struct Lms400Options {
  Vec3d position = Vec3d(0, -0.8, 0.65);
  double heading_deg = 90;         // direction of the level forward axis in the xy plane (+y)
  double fov_deg = 70;             // the LMS400's scan line
  double angular_step_deg = 0.12;  // within a line
  double pitch_near_deg = 60;      // downward tilt of the first line (steepest)
  double pitch_far_deg = 30;       // and of the last
  double pitch_step_deg = 0.14;    // tilt between lines (lms400_for_scene derives `lines`)
  int lines = 250;
  double range_noise = 0.0005;    // Gaussian sigma along the beam (m)
  double dropout = 0.002;         // probability a return is lost
  double max_incidence_deg = 85;  // no return at more grazing angles
  double min_range = 0.7, max_range = 3.0;
};

// Where a sensor stands, beyond the seed's small jitter (augmentation: other ranges and
// incidences). Its offset from the table's front edge (back and up) is scaled by range_scale and
// turned about the edge by elevation_deg (positive: higher, looking down more steeply).
struct SensorPlacement {
  double range_scale = 1.0;
  double elevation_deg = 0.0;
};

// A scanner pose in front of the table (with a little seed-dependent variation in position and
// heading) and a sweep over the region of the table the objects stand on, with a margin.
Lms400Options lms400_for_scene(const Scene& scene, std::uint64_t seed,
                               const SensorPlacement& placement = {});

PointCloud scan_lms400(const Scene& scene, const Lms400Options& options, double label_radius,
                       std::uint64_t seed);

// Kinect-like structured-light depth camera: organised width x height (NaN where there is no
// return), depth noise sigma = depth_noise * z^2 (Khoshelham & Elberink 2012) and quantisation to
// 1/subpixel of a disparity pixel, shadows where the projector does not light the surface.
//
// The error model is calibrated on the table planes of the 45 mOSD learning scenes
// (primlabel-research calibrate-kinect --fit-simulation, docs/results.md "Kinect calibration"):
// depth levels are z^2 / F apart with F = disparity_focal_px * baseline * subpixel = 344.9 m px
// measured (0.5% rms over 0.6-1.7 m); the error is correlated over ~3.5 px (autocorrelation
// 0.70 / 0.55 / 0.34 at 1 / 2 / 4 px), and depth_noise is what makes simulated frames show the
// real residual to 24-px tile planes, 1.70e-3 * z^2 (tiles absorb part of a correlated error).
// The values before the calibration: depth_noise 1.425e-3, white, disparity in focal_px (F = 315).
struct KinectOptions {
  Vec3d position = Vec3d(0, -0.85, 0.75);
  Vec3d target = Vec3d(0, 0.05, 0);
  int width = 640, height = 480;
  double focal_px = 525;  // the image the depth is registered to; at 640 px width, scaled with it
  // Disparity is measured in the IR camera's pixels, whose focal length differs from the
  // registered image's (the Kinect's IR camera: ~580 px); at 640 px width, scaled with it.
  double disparity_focal_px = 575;
  double depth_noise = 2.25e-3;
  // The real error is spatially correlated (a disparity is matched over a window of pixels): the
  // unit error is sqrt(independent_noise_share) white noise plus the rest white noise blurred by a
  // Gaussian of std noise_correlation_px (each of unit variance). 0 px: every pixel on its own.
  double noise_correlation_px = 3.5;
  double independent_noise_share = 0.05;
  bool quantize = true;
  double baseline = 0.075;  // camera-projector distance (m)
  int subpixel = 8;
  bool projector_shadow = true;
  double dropout = 0.0;
  double max_incidence_deg = 85;
  double min_range = 0.5, max_range = 4.0;
};

KinectOptions kinect_for_scene(const Scene& scene, std::uint64_t seed,
                               const SensorPlacement& placement = {});

PointCloud scan_kinect(const Scene& scene, const KinectOptions& options, double label_radius,
                       std::uint64_t seed);

}  // namespace primlabel::synth
