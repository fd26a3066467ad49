#pragma once
// What a cloud shows of the sensor that made it, measured on the points as acquired (before any
// voxel filter): how far apart they are, how rough a flat patch looks, and how that roughness
// grows with range (a depth camera's noise grows with the square of the range, a laser
// scanner's hardly at all, whatever their noise level). A model records the range of these over
// its training scans, so a request that names no model can go to the model whose sensor looks
// like the cloud's (pipeline/model_choice.hpp). They do not depend on a model's voxel size or
// radii, so one measurement compares a cloud with every model.

#include <cstddef>
#include <limits>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel {

// The radius (m) of the patches whose roughness is measured: a few times a depth camera's point
// spacing at table range, small enough that most patches of a table-top scene are flat.
inline constexpr float kRoughnessRadius = 0.01f;
// Patches with fewer points say nothing about the noise.
inline constexpr std::size_t kRoughnessMinPoints = 8;
// The noise growth is measured only when the far half of the patches lies at least this factor
// farther than the near half (else the range says nothing about it).
inline constexpr float kNoiseGrowthMinRangeRatio = 1.15f;

struct CloudSignature {
  float point_spacing = 0;  // median distance to the nearest distinct point (m); NaN: none
  // Median over sampled points of the RMS distance of their kRoughnessRadius neighbourhood to its
  // least-squares plane (m): on the planes that dominate most scenes, the range noise. NaN when
  // no patch held kRoughnessMinPoints.
  float roughness = 0;
  // The exponent g of noise ~ range^g between the near and the far half of the patches, the noise
  // being a patch's roughness over the cosine of its incidence (the noise along the ray; patches
  // seen more obliquely than 72 degrees left out) and each half summarised by its lower quartile
  // (where the flat patches are): about 2 for a depth camera, about 0 for a laser scanner. NaN
  // when the two halves' ranges are too alike or there are too few patches.
  float noise_growth = std::numeric_limits<float>::quiet_NaN();
  // Of the nearest neighbours of sampled points on slanted patches (normal at least
  // kTiesMinSlant degrees from the frame's z axis), the fraction at exactly the same z: a depth
  // camera quantises depth (to disparity steps, or to whole millimetres), so neighbours share
  // levels even where the surface slopes, while a laser scanner's or a simulator's continuous
  // depths hardly ever tie. It reads depth along the frame's z axis, a camera frame's; a cloud
  // turned into another frame loses its ties, so only their presence says something. NaN when
  // fewer than kTiesMinPatches sampled patches are slanted, or when x and y lie on a decimal grid
  // too (coordinates rounded for storage tie in every axis: not a sensor's quantisation).
  float depth_ties = std::numeric_limits<float>::quiet_NaN();
};

inline constexpr float kTiesMinSlant = 25.0f;
inline constexpr std::size_t kTiesMinPatches = 32;

// Over an evenly strided sample of at most `max_samples` finite points (the same figures for
// any thread count); ranges from `viewpoint`, the sensor's origin. Builds a neighbour index on
// `xyz`: tens of milliseconds for a 640x480 frame. Throws Cancelled when context.stop is
// requested.
CloudSignature measure_signature(const std::vector<Vec3f>& xyz, const Vec3f& viewpoint,
                                 const RunContext& context = {}, std::size_t max_samples = 2048);

}  // namespace primlabel
