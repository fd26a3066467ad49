#pragma once
// From a labeled cloud to primitive instances: segment_by_label, then every segment fitted with
// its class's model (model_for_class) in parallel, each from a seed of its own, so the result
// is the same for any thread count. Unknown points (label 0) form no segment; corners get a
// kSegment primitive (centroid and bounds only); a segment whose fit fails keeps its centroid
// and bounds with confidence 0.

#include <cstdint>
#include <span>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/primitives/fitters.hpp"
#include "primlabel/primitives/primitive.hpp"
#include "primlabel/primitives/segmentation.hpp"

namespace primlabel::primitives {

struct PrimitiveOptions {
  SegmentOptions segments;
  FitSettings fit;
  std::uint64_t seed = 1;

  void validate() const;
};

struct PrimitiveSet {
  std::vector<Primitive> primitives;         // primitives[s] is segment s
  std::vector<std::uint32_t> point_segment;  // per point; kNoSegment when none
  float segment_radius = 0.0f;
  double segment_seconds = 0, fit_seconds = 0;
};

// `normals` may be empty (then only planes and lines are fitted; the curved models need them) or
// hold one entry per point. Throws std::invalid_argument for mismatched sizes or bad options,
// Cancelled when context.stop is requested (checked per segment). `shared`: what the labeling
// already built on `xyz` (segment_by_label reuses it; the result is the same).
PrimitiveSet fit_primitives(const std::vector<Vec3f>& xyz, std::span<const Vec3f> normals,
                            std::span<const std::uint32_t> labels, const PrimitiveOptions& options,
                            const RunContext& context = {}, const SharedNeighbors& shared = {});

}  // namespace primlabel::primitives
