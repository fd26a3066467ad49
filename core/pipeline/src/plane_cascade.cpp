// The plane cascade's split of a described cloud (plane_cascade.hpp).

#include "plane_cascade.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/parallel.hpp"
#include "primlabel/geometry/point_moments.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::pipeline {

namespace {
constexpr std::size_t kBlock = 512;  // points per parallel block
// A dense scan holds hundreds of points within the labeling scale, and telling a plane from a
// curved surface needs far fewer: the variation is measured on voxel centroids this many to a
// radius and every point takes its voxel's (unless the voxels would save little).
constexpr float kVoxelsPerRadius = 6.0f;

// The neighbours of point p within `hood`, from the lists when they hold that radius.
void neighbors_within(const std::vector<Vec3f>& xyz, std::size_t p, const Neighborhood& hood,
                      const NeighborSearch& search, const NeighborLists* lists, NeighborList& out) {
  if (lists && hood.radius <= lists->neighborhood().radius)
    lists->find(p, hood, out);
  else
    search.find(xyz[p], hood, out, /*sorted=*/false);
}

// Per point of `points` its neighbourhood's variation within `hood` (NaN: fewer than 3 points).
std::vector<float> variations_of(const std::vector<Vec3f>& points, const Neighborhood& hood,
                                 const NeighborSearch& search, const NeighborLists* lists,
                                 const RunContext& context) {
  const std::size_t n = points.size();
  std::vector<float> out(n, std::numeric_limits<float>::quiet_NaN());
  const std::ptrdiff_t blocks = std::ptrdiff_t((n + kBlock - 1) / kBlock);
  detail::for_each_block(
      blocks, context, [] { return NeighborList(); },
      [&](NeighborList& list, std::ptrdiff_t block) {
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        for (std::size_t p = first; p < last; ++p) {
          if (!is_finite(points[p])) continue;
          neighbors_within(points, p, hood, search, lists, list);
          PointMoments moments;
          for (std::uint32_t q : list.indices) moments.add(points[q], points[p]);
          out[p] = float(moments.surface_variation());  // NaN: undefined
        }
      });
  throw_if_stopped(context.stop, "the plane cascade");
  return out;
}

}  // namespace

float cascade_max_variation(float median, const CascadeNoise& noise, const CascadeScale& scale) {
  float bound = 0.0f;
  if (scale.is_normal_radius && noise.normal_variation > 0.0f)
    bound = noise.normal_variation;
  else if (noise.roughness > 0.0f && scale.radius > 0.0f)
    bound = 2.0f * noise.roughness * noise.roughness / (scale.radius * scale.radius);
  if (!(median > 0.0f) || !(bound > 0.0f)) return 0.0f;
  return kCascadeNoiseFactor * std::min(median, bound);
}

std::vector<float> surface_variations(const std::vector<Vec3f>& xyz, float radius,
                                      const NeighborSearch& search, const NeighborLists* lists,
                                      const RunContext& context) {
  const Neighborhood hood = capped(Neighborhood::Radius(radius));
  const tabletop::VoxelGrid grid = tabletop::voxel_downsample(
      xyz, tabletop::finite_indices(xyz), radius / kVoxelsPerRadius, context);
  if (2 * grid.centroids.size() > xyz.size())
    return variations_of(xyz, hood, search, lists, context);
  const NeighborSearch centroid_search(grid.centroids, context.stop);
  const std::vector<float> per_voxel =
      variations_of(grid.centroids, hood, centroid_search, nullptr, context);
  std::vector<float> out(xyz.size(), std::numeric_limits<float>::quiet_NaN());
  for (std::size_t i = 0; i < xyz.size(); ++i)
    if (grid.voxel_of_point[i] != tabletop::kNoVoxel) out[i] = per_voxel[grid.voxel_of_point[i]];
  return out;
}

std::vector<std::uint8_t> cascaded_planes(const PointCloud& cloud,
                                          const std::vector<float>& variation, float max_variation,
                                          float ring_radius, const NeighborSearch& search,
                                          const NeighborLists* lists, const RunContext& context) {
  const std::size_t n = cloud.size();
  std::vector<std::uint8_t> cascaded(n, 0);
  if (!(max_variation > 0.0f) || variation.size() != n || cloud.normals.size() != n)
    return cascaded;
  for (std::size_t i = 0; i < n; ++i)
    cascaded[i] = is_finite(cloud.xyz[i]) && is_finite(cloud.normals[i]) &&
                  variation[i] < max_variation;  // NaN variation: not planar
  // The ring: every planar point within ring_radius of a point that is not goes to the CRF.
  // Marks are only ever cleared, so the result does not depend on the order or the threads.
  const Neighborhood ring = capped(Neighborhood::Radius(ring_radius));
  const std::vector<std::uint8_t> planar = cascaded;
  const std::ptrdiff_t blocks = std::ptrdiff_t((n + kBlock - 1) / kBlock);
  detail::for_each_block(
      blocks, context, [] { return NeighborList(); },
      [&](NeighborList& scratch, std::ptrdiff_t block) {
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        for (std::size_t p = first; p < last; ++p) {
          if (planar[p] || !is_finite(cloud.xyz[p])) continue;
          neighbors_within(cloud.xyz, p, ring, search, lists, scratch);
          for (std::uint32_t q : scratch.indices)
            std::atomic_ref<std::uint8_t>(cascaded[q]).store(0, std::memory_order_relaxed);
        }
      });
  throw_if_stopped(context.stop, "the plane cascade");
  return cascaded;
}

}  // namespace primlabel::pipeline
