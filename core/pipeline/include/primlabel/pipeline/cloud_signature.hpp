#pragma once
// What a cloud shows of the sensor that made it, measured on the points as acquired (before any
// voxel filter): how far apart they are and how rough a flat patch looks. A model records the
// range of both over its training scans, so a request that names no model can go to the model
// whose sensor looks like the cloud's (model_choice.hpp). Unlike the described spacing and
// surface variation of domain.hpp, these do not depend on a model's voxel size or radii, so one
// measurement compares a cloud with every model.

#include <cstddef>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::pipeline {

// The radius (m) of the patches whose roughness is measured: a few times a depth camera's point
// spacing at table range, small enough that most patches of a table-top scene are flat.
inline constexpr float kRoughnessRadius = 0.01f;
// Patches with fewer points say nothing about the noise.
inline constexpr std::size_t kRoughnessMinPoints = 8;

struct CloudSignature {
  float point_spacing = 0;  // median distance to the nearest distinct point (m); NaN: none
  // Median over sampled points of the RMS distance of their kRoughnessRadius neighbourhood to its
  // least-squares plane (m): on the planes that dominate most scenes, the range noise. NaN when
  // no patch held kRoughnessMinPoints.
  float roughness = 0;
};

// Over an evenly strided sample of at most `max_samples` finite points (the same figures for
// any thread count). Builds a neighbour index on `xyz`: tens of milliseconds for a 640x480
// frame. Throws Cancelled when context.stop is requested.
CloudSignature measure_signature(const std::vector<Vec3f>& xyz, const RunContext& context = {},
                                 std::size_t max_samples = 2048);

}  // namespace primlabel::pipeline
