#pragma once
// Surface normals by PCA of each point's neighbourhood (the eigenvector of the smallest eigenvalue
// of the neighbourhood covariance), oriented toward a viewpoint, and curvature
// lambda0 / (lambda0 + lambda1 + lambda2). Matches PCL's NormalEstimation.

#include <cstdint>
#include <optional>
#include <span>

#include "primlabel/geometry/neighbor_lists.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/progress.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel {

struct NormalOptions {
  Neighborhood neighborhood = Neighborhood::Knn(10);
  // Normals are flipped to face this point; defaults to the cloud's VIEWPOINT origin.
  std::optional<Vec3f> viewpoint;
  // Per point, whether it wants a normal (empty: all); the others keep NaN and are not counted.
  // Their coordinates still serve as neighbours.
  std::span<const std::uint8_t> wanted;
};

struct NormalStats {
  std::size_t estimated = 0;      // points that got a finite normal
  std::size_t too_few = 0;        // fewer than 3 neighbours, or all coincident: NaN normal
  std::size_t invalid_input = 0;  // points with non-finite coordinates: NaN normal
};

// Fills cloud.normals and cloud.curvature (one per point). Points that cannot get a normal get NaN
// normal and NaN curvature and are counted in the returned stats. `search` may be passed to reuse
// an index built on cloud.xyz, and `lists` shared neighbour lists on it (used when the
// neighbourhood is a radius within theirs; the same neighbours, no second search). Once
// context.stop is requested the remaining points are skipped and estimate_normals throws Cancelled;
// context.progress counts points.
NormalStats estimate_normals(PointCloud& cloud, const NormalOptions& options,
                             const RunContext& context = {}, const NeighborSearch* search = nullptr,
                             const NeighborLists* lists = nullptr);

}  // namespace primlabel
