#pragma once
// The model input of multi-scale FeatureSettings: the descriptor at the feature radius, the same
// descriptor at each further radius, then (optionally) the point's surface variation at the
// normal, feature and further radii. Real surfaces (rounded box corners, printed labels, depth
// noise that grows with range) look different at different scales; one 25 mm FPFH cannot tell a
// rounded corner from a noisy edge.

#include <cstdint>
#include <span>

#include "primlabel/geometry/descriptors.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/model/label_model.hpp"

namespace primlabel::pipeline {

// Surface variation is at most 1/3; scaled by this it spans the FPFH bins' 0..100, so the
// model's feature scale and node knots suit it too.
inline constexpr float kSurfaceVariationScale = 300.0f;

// `descriptors` (the descriptor at the feature radius, cloud.size() rows) widened to
// settings.model_input_dim() values a point. Needs cloud.normals; `search` indexes cloud.xyz.
// `curvature_at_normal_radius`: cloud.curvature is estimate_normals' at the model's normal
// radius, so it is the first variation (else that is measured too). A point whose descriptor is
// NaN keeps an all-NaN row; a variation that cannot be measured (too few neighbours) is 0.
// `wanted` (empty: every point): only the points marked non-zero are widened, the others keep
// their (NaN) rows, as FeatureOptions::wanted.
Descriptors multi_scale_input(const PointCloud& cloud, Descriptors descriptors,
                              const FeatureSettings& settings, const NeighborSearch& search,
                              bool curvature_at_normal_radius, std::span<const std::uint8_t> wanted,
                              const RunContext& context);

// The first `dim` values of each row: what clients get back as the descriptor.
Descriptors leading_values(Descriptors descriptors, int dim);

}  // namespace primlabel::pipeline
