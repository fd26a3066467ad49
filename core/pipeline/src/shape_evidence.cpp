// The table-top objects fitted with boxes and cylinders, as per-point model input
// (shape_evidence.hpp).

#include "primlabel/pipeline/shape_evidence.hpp"

#include <cmath>
#include <stdexcept>

#include "primlabel/model/label_model.hpp"
#include "primlabel/synth/fitted_truth.hpp"
#include "primlabel/tabletop/tabletop.hpp"

namespace primlabel::pipeline {

namespace {
// An FPFH bin is a percentage: evidence on the same scale suits the model's feature scale and
// node knots.
constexpr float kEvidenceValue = 100.0f;
}  // namespace

std::vector<std::uint32_t> shape_evidence(const PointCloud& cloud, const RunContext& context,
                                          const NeighborSearch* search) {
  std::vector<std::uint32_t> none(cloud.size(), 0u);
  const tabletop::TabletopResult objects =
      tabletop::segment_tabletop(cloud, tabletop::TabletopOptions{}, context);
  if (!objects.ok() || objects.clusters.empty()) return none;
  const std::vector<std::int32_t> ids = tabletop::segment_ids(objects, cloud.size());
  const std::vector<int> segments(ids.begin(), ids.end());
  try {
    return synth::fit_object_truth(cloud, segments, synth::ObjectTruthOptions{}, context, search)
        .labels;
  } catch (const std::invalid_argument&) {
    return none;  // no table plane among the table's points: no frame to fit shapes in
  }
}

Descriptors with_shape_evidence(const PointCloud& cloud, Descriptors descriptors,
                                const RunContext& context, const NeighborSearch* search) {
  const std::vector<std::uint32_t> evidence = shape_evidence(cloud, context, search);
  const std::size_t n = descriptors.size();
  const int d = descriptors.dim;
  Descriptors out = Descriptors::filled(n, d + kShapeEvidenceDim, std::nanf(""));
  for (std::size_t i = 0; i < n; ++i) {
    const std::span<const float> row = descriptors.row(i);
    if (!std::isfinite(row[0])) continue;  // no descriptor: stays invalid
    const std::span<float> widened = out.row(i);
    std::copy(row.begin(), row.end(), widened.begin());
    std::fill(widened.begin() + d, widened.end(), 0.0f);
    const std::uint32_t c = evidence[i];
    if (c >= 1 && c <= std::uint32_t(kShapeEvidenceDim))
      widened[std::size_t(d) + c - 1] = kEvidenceValue;
  }
  return out;
}

}  // namespace primlabel::pipeline
