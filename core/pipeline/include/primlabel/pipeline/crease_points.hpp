#pragma once
// Per-point answers near creases (LabelingOptions::crease_points). A voxel that a crease cuts
// holds points of both sides, and its one answer is wrong for the minority side: at 7 mm voxels
// the true majority of every voxel is right for only ~95% of a Kinect frame's points. Where a
// described voxel has a neighbour with another label, each of its input points is instead
// decided at its own position from the CRF marginals of the nearest described voxels, weighted
// by inverse squared distance (PointNet++'s feature propagation); every other point keeps its
// voxel's answer, so the cost is only paid at creases.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::pipeline {

// Described voxels interpolated per point (4 measured better than 3 and 6 on Kinect frames).
inline constexpr int kCreaseNeighbors = 4;
// A voxel is at a crease when one of its nearest 26 described voxels within this many voxel
// edges, centroid to centroid, has another label: the 26 adjacent cells' centres lie within
// sqrt(3) edges. 1.5 and 2 decided the same points' labels on the measured scenes.
inline constexpr float kCreaseReach = 1.75f;

// The answers of the voxels (slots) the CRF labeled, one row per slot.
struct SlotAnswers {
  const std::vector<Vec3f>* xyz = nullptr;  // slot positions, indexed by `search`
  const NeighborSearch* search = nullptr;
  std::span<const std::uint8_t> inferred;      // 1: the CRF labeled the slot (it has marginals)
  std::span<const std::uint32_t> labels;       // taxonomy ids
  const Eigen::MatrixXf* marginals = nullptr;  // slots x K, columns in class_ids' order
  std::span<const std::uint32_t> class_ids;
};

// The input points decided on their own, ascending, with their labels and probabilities (the
// interpolated marginals, rows sum to 1; the label is their argmax, ties to the lowest column).
struct CreaseAnswers {
  std::vector<std::uint32_t> points;
  std::vector<std::uint32_t> labels;
  Eigen::MatrixXf probabilities;  // points.size() x K
};

// `points`: the input cloud's coordinates; `slot_of`: per input point its slot (or
// tabletop::kNoVoxel); `voxel_size` > 0 the edge the slots were made with. Only points whose slot
// was inferred are decided. The result does not depend on context.threads; throws Cancelled
// when context.stop is requested.
CreaseAnswers decide_crease_points(const std::vector<Vec3f>& points,
                                   std::span<const std::uint32_t> slot_of, const SlotAnswers& slots,
                                   float voxel_size, const RunContext& context = {});

}  // namespace primlabel::pipeline
