#pragma once
// Where every input point of label_cloud takes its answer from. Three maps are composed once:
// the table-top stage on the input (only the table and its objects are labeled), voxel
// downsampling (a voxel's centroid stands for its members) and exact duplicates (duplicates.hpp:
// one representative per position, the lowest index), in that order, each on what the one before
// kept. The described cloud holds one point per slot; every input point has a slot, or none and
// stays unknown.

#include <cstdint>
#include <optional>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/tabletop/tabletop_objects.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::pipeline {

inline constexpr std::uint32_t kNoSlot = tabletop::kNoVoxel;

struct LabelingPlan {
  // Nothing merged or dropped: the input cloud itself is described, in place (its layout, its
  // curvature and the normals written into it are those of the input), and slot i is point i.
  bool in_place = false;
  // Otherwise the points to describe, one per slot: unorganised, with the input's viewpoint and,
  // with the cloud's own normals, the normals of the points they stand for.
  PointCloud described;
  std::vector<std::uint32_t> slot_of;  // per input point its slot or kNoSlot; empty when in_place
  bool merges_points = false;          // some slot stands for several input points
  float voxel_size = 0.0f;             // the voxels' edge; 0: no voxels
  // With want_objects: the table-top stage's object id of every input point (the counts and
  // shapes are left to describe_objects).
  std::optional<tabletop::TabletopObjects> objects;
  StageSeconds seconds;  // its voxels, table-top and duplicates stages

  PointCloud& described_cloud(PointCloud& input) { return in_place ? input : described; }
};

// `voxel_size` > 0 downsamples; options.tabletop_only keeps only the table-top stage's table and
// objects. Throws what voxel_downsample and segment_tabletop throw (Cancelled included).
LabelingPlan plan_labeling(const PointCloud& cloud, float voxel_size,
                           const LabelingOptions& options, const RunContext& context);

}  // namespace primlabel::pipeline
