#pragma once
// The plane cascade (LabelingOptions::plane_cascade): on a table-top scene most points lie on
// planes, and a plane needs neither a descriptor nor a CRF node to be called one. A point whose
// neighbourhood at the labeling scale (the larger of the model's normal and feature radii: the
// scale its descriptor tells classes apart at) is planar within the noise of planes is labeled
// plane directly; descriptors and inference run on the rest and on a ring around it (the feature
// radius), so that every point the CRF labels keeps its planar neighbours as context.

#include <cstdint>
#include <vector>

#include "primlabel/geometry/neighbor_lists.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::pipeline {

// How far above the noise of planes a planar point's surface variation may lie: the median
// variation of a table-top scene is that of its planes (they hold most points), and a noisy
// plane's variation spreads about it by a factor of a few.
inline constexpr float kCascadeNoiseFactor = 3.0f;

// The noise the model's training scans showed (TrainingSummary), which bounds what the cascade
// may call planar: a scene of mostly curved surfaces has a median variation far above any
// plane's.
struct CascadeNoise {
  float roughness = 0;         // the greatest roughness of the training scans (m); 0: unknown
  float normal_variation = 0;  // the greatest median variation at the normal radius; 0: unknown
};

struct CascadeScale {
  float radius = 0;               // the labeling scale (m)
  bool is_normal_radius = false;  // cloud.curvature is the variation at it
};

// The largest surface variation at scale.radius the cascade calls planar on a cloud whose
// median variation there is `median`: kCascadeNoiseFactor times the lesser of the median and
// the training scans' own: their greatest median variation when the scale is the normal radius
// (measured at that very scale, a depth camera's correlated noise included), else the
// variation a plane with their roughness shows at that radius (about 2 roughness^2 / radius^2;
// roughness is measured over 1 cm patches, so it misses noise that is correlated over larger
// ones). 0 (no cascade) when neither is known.
float cascade_max_variation(float median, const CascadeNoise& noise, const CascadeScale& scale);

// Per point the surface variation (PCA smallest eigenvalue over their sum) of its neighbourhood
// within `radius`, measured on voxel centroids a sixth of the radius apart when that saves most
// of the points (a dense scan), else on the points themselves; NaN for non-finite points and
// neighbourhoods of fewer than 3 points. `lists` may be null or hold a smaller radius (then
// `search` answers).
std::vector<float> surface_variations(const std::vector<Vec3f>& xyz, float radius,
                                      const NeighborSearch& search, const NeighborLists* lists,
                                      const RunContext& context);

// Per point: 1 when the cascade labels it plane (finite, with a normal, variation below
// max_variation, and no point above it within ring_radius), else 0. Throws Cancelled when
// context.stop is requested.
std::vector<std::uint8_t> cascaded_planes(const PointCloud& cloud,
                                          const std::vector<float>& variation, float max_variation,
                                          float ring_radius, const NeighborSearch& search,
                                          const NeighborLists* lists, const RunContext& context);

}  // namespace primlabel::pipeline
