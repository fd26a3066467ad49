#pragma once
// Shape evidence (FeatureSettings::shape_evidence): what the object's shape says about a point.
// A per-point model cannot see most corners of a box: its third face is hidden from the sensor,
// so its neighbourhood looks like an edge's. The object's fitted shape can: the table-top stage's
// objects are fitted with boxes and upright or lying cylinders (synth/fitted_truth.hpp, the
// fitter of the real scenes' ground truth, accepting only fits that explain the points), and the
// taxonomy's own rule labels every point a fitted surface explains, hidden faces included. That
// label enters the model as kShapeEvidenceDim more input values; training learns how far to
// trust it. Training and labeling compute it the same way, on the cloud that is described.

#include <cstdint>
#include <vector>

#include "primlabel/geometry/descriptors.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::pipeline {

// Per point of `cloud` the taxonomy class id its object's fitted shape gives it, 0 (unknown)
// where no fitted surface explains it: no table, no object, or no fit accepted. Deterministic
// whatever context.threads; throws Cancelled when context.stop is requested. `search`, an index
// on cloud.xyz, saves building one.
std::vector<std::uint32_t> shape_evidence(const PointCloud& cloud, const RunContext& context,
                                          const NeighborSearch* search = nullptr);

// `descriptors` (one row per point of `cloud`) widened by kShapeEvidenceDim values: 100 (the
// scale of an FPFH bin's percentage) in the column of the point's evidence class, 0 elsewhere.
// Rows without a descriptor (NaN) stay NaN.
Descriptors with_shape_evidence(const PointCloud& cloud, Descriptors descriptors,
                                const RunContext& context, const NeighborSearch* search = nullptr);

}  // namespace primlabel::pipeline
