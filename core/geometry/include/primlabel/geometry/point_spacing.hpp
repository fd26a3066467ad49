#pragma once
// How far apart a cloud's points are: the median distance from a point to its nearest other
// point, over an evenly strided sample. A model trained at one spacing misreads clouds far
// denser or sparser than that (its radii then hold other shapes), so the pipeline measures it.

#include <cstddef>
#include <vector>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel {

// `search` must be built on `xyz`. Coincident copies are skipped (the nearest point at a distance
// above zero counts). The sample is every (n / max_samples)-th finite point, so the figure is
// the same for any thread count and costs max_samples small queries. NaN when no point has a
// distinct neighbour.
float median_point_spacing(const std::vector<Vec3f>& xyz, const NeighborSearch& search,
                           std::size_t max_samples = 4096);

// The median of the finite values of `curvature` (surface variation from normals.hpp) over the
// same kind of strided sample: on the planes that dominate most scenes it grows with the square of
// the range noise relative to the normal radius. NaN when none is finite.
float median_surface_variation(const std::vector<float>& curvature, std::size_t max_samples = 4096);

}  // namespace primlabel
