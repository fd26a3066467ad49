#pragma once
// Connected components of same-class points: two points belong to one segment when they carry
// the same label and lie within `radius` of each other (directly or through a chain of such
// points). The partition does not depend on the thread count, and segments are numbered by size
// (largest first), ties by their lowest point index.

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "primlabel/geometry/neighbor_lists.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::primitives {

inline constexpr std::uint32_t kNoSegment = 0xFFFFFFFFu;

struct SegmentOptions {
  // Linking distance (m); 0 = 4x the cloud's median point spacing (at least 1 mm).
  float radius = 0.0f;
  // Nearest same-cloud neighbours looked at per point, within radius. The default is the
  // pipeline's own cap (pipeline::kDefaultMaxNeighbors), so its shared lists answer the linking
  // neighbourhood without a search of its own (SharedNeighbors).
  int max_neighbors = 1024;
  std::size_t min_points = 30;      // smaller components get no segment
  std::size_t max_segments = 4096;  // the largest kept, the rest get no segment
  bool skip_unknown = true;         // label 0 (unknown) forms no segments

  void validate() const;  // throws std::invalid_argument
};

struct Segmentation {
  std::vector<std::vector<std::uint32_t>> segments;  // ascending point indices per segment
  std::vector<std::uint32_t> labels;                 // each segment's label
  std::vector<std::uint32_t> point_segment;          // per point; kNoSegment when none
  float radius = 0.0f;                               // the linking distance used
};

// What the labeling pipeline already built on the same points, to reuse instead of building
// again: its neighbour index, its shared radius lists (answering the linking neighbourhood when
// it lies within their radius, with the same neighbour set as a search) and the median point
// spacing median_point_spacing measured with that index. Any may be null / NaN. The result is
// the same with or without them.
struct SharedNeighbors {
  const NeighborSearch* search = nullptr;  // indexes exactly the points being segmented
  const NeighborLists* lists = nullptr;    // built with `search` on those points
  float point_spacing = std::numeric_limits<float>::quiet_NaN();
};

// `labels` has one entry per point of `xyz`; non-finite points get no segment. Throws
// std::invalid_argument for mismatched sizes or bad options, Cancelled when context.stop is
// requested.
Segmentation segment_by_label(const std::vector<Vec3f>& xyz, std::span<const std::uint32_t> labels,
                              const SegmentOptions& options, const RunContext& context = {},
                              const SharedNeighbors& shared = {});

}  // namespace primlabel::primitives
