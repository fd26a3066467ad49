// The plan of label_cloud: voxels, the table-top stage and exact duplicates composed into one slot
// per input point, and the one cloud of slots to describe.

#include "labeling_plan.hpp"

#include <chrono>
#include <limits>
#include <numeric>
#include <optional>

#include "primlabel/pipeline/duplicates.hpp"
#include "primlabel/tabletop/tabletop.hpp"

namespace primlabel::pipeline {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Voxel centroids, with the mean of the members' normals (normalised) when the cloud's own
// normals are used.
PointCloud voxel_cloud(const PointCloud& cloud, const tabletop::VoxelGrid& grid,
                       bool with_normals) {
  PointCloud voxels;
  voxels.resize_unorganized(grid.centroids.size());
  voxels.xyz = grid.centroids;
  voxels.viewpoint = cloud.viewpoint;
  if (!with_normals) return voxels;
  voxels.normals.assign(grid.centroids.size(), Vec3f::Constant(kNaN));
  for (std::size_t v = 0; v < grid.centroids.size(); ++v) {
    Vec3f sum = Vec3f::Zero();
    for (std::uint32_t m = grid.member_offsets[v]; m < grid.member_offsets[v + 1]; ++m) {
      const Vec3f& n = cloud.normals[grid.members[m]];
      if (is_finite(n)) sum += n;
    }
    if (sum.norm() > 0.0f) voxels.normals[v] = sum.normalized();
  }
  return voxels;
}

// The points `indices` of `cloud` as a cloud of their own (unorganised, same viewpoint), with
// their normals when the cloud's own normals are used.
PointCloud gather(const PointCloud& cloud, const std::vector<std::uint32_t>& indices,
                  bool with_normals) {
  PointCloud part;
  part.resize_unorganized(indices.size());
  part.viewpoint = cloud.viewpoint;
  for (std::size_t j = 0; j < indices.size(); ++j) part.xyz[j] = cloud.xyz[indices[j]];
  if (with_normals) {
    part.normals.resize(indices.size());
    for (std::size_t j = 0; j < indices.size(); ++j) part.normals[j] = cloud.normals[indices[j]];
  }
  return part;
}

// The points a table-top mask keeps, ascending, and per point its position among them.
struct Kept {
  std::vector<std::uint32_t> points;
  std::vector<std::uint32_t> position_of;  // kNoSlot: not kept
};

Kept kept_points(const std::vector<std::uint8_t>& mask) {
  Kept kept;
  kept.position_of.assign(mask.size(), kNoSlot);
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) {
      kept.position_of[i] = static_cast<std::uint32_t>(kept.points.size());
      kept.points.push_back(static_cast<std::uint32_t>(i));
    }
  return kept;
}

// Sends every slot through the next map (kNoSlot stays).
void compose(std::vector<std::uint32_t>& slot_of, const std::vector<std::uint32_t>& next) {
  for (std::uint32_t& slot : slot_of)
    if (slot != kNoSlot) slot = next[slot];
}

std::vector<std::uint32_t> identity(std::size_t n) {
  std::vector<std::uint32_t> map(n);
  std::iota(map.begin(), map.end(), 0u);
  return map;
}

}  // namespace

LabelingPlan plan_labeling(const PointCloud& cloud, float voxel_size,
                           const LabelingOptions& options, const RunContext& context) {
  LabelingPlan plan;
  const bool with_normals = options.use_cloud_normals;

  // 1. The table-top stage on the input itself, as primlabel-tabletop runs it, so both give the
  // same objects (its image steps need the organised frame, not voxels): only its table and
  // objects are kept.
  std::optional<Kept> kept;
  if (options.tabletop_only) {
    const auto tabletop_start = std::chrono::steady_clock::now();
    const tabletop::TabletopResult segmented =
        tabletop::segment_tabletop(cloud, tabletop::TabletopOptions{}, context);
    kept = kept_points(tabletop::tabletop_mask(segmented, cloud.size()));
    if (options.want_objects) plan.objects = tabletop::object_ids(segmented, cloud.size());
    plan.seconds.tabletop = seconds_since(tabletop_start);
    context.throw_if_stopped("labeling");
  }

  // 2. Voxels of the kept points: a centroid stands for its voxel's members (non-finite points
  // are in none).
  const auto voxels_start = std::chrono::steady_clock::now();
  std::optional<PointCloud> voxels;
  std::vector<std::uint32_t> voxel_of_point;
  if (voxel_size > 0.0f) {
    tabletop::VoxelGrid grid = tabletop::voxel_downsample(
        cloud.xyz, kept ? kept->points : tabletop::finite_indices(cloud.xyz), voxel_size, context);
    voxels = voxel_cloud(cloud, grid, with_normals);
    voxel_of_point = std::move(grid.voxel_of_point);
    plan.voxel_size = voxel_size;
    plan.seconds.voxels = seconds_since(voxels_start);
    context.throw_if_stopped("labeling");
  }

  // 3. Exact duplicates among what is left: one slot per position. Its time includes the slot
  // map and the gather below.
  const auto duplicates_start = std::chrono::steady_clock::now();
  const PointCloud& base = voxels ? *voxels : cloud;
  const bool kept_input = kept && !voxels;  // the voxels hold only kept points already
  const DuplicateMap duplicates = kept_input ? find_duplicates(base.xyz, kept->points, context.stop)
                                             : find_duplicates(base.xyz, context.stop);
  plan.merges_points = voxels || duplicates.any();
  if (!voxels && !kept && !duplicates.any()) {
    plan.in_place = true;
    plan.seconds.duplicates = seconds_since(duplicates_start);
    return plan;
  }

  // 4. Per input point its slot: input -> voxel or kept point -> distinct position.
  plan.slot_of = voxels ? std::move(voxel_of_point) : identity(cloud.size());
  if (kept_input) compose(plan.slot_of, kept->position_of);
  compose(plan.slot_of, duplicates.slot_of);

  // 5. The one cloud to describe: every slot's representative.
  if (voxels && !duplicates.any()) {
    plan.described = std::move(*voxels);  // every voxel is its own slot
    plan.seconds.duplicates = seconds_since(duplicates_start);
    return plan;
  }
  std::vector<std::uint32_t> representatives = duplicates.representatives;
  if (kept_input) compose(representatives, kept->points);
  plan.described = gather(base, representatives, with_normals);
  plan.seconds.duplicates = seconds_since(duplicates_start);
  return plan;
}

}  // namespace primlabel::pipeline
