#include "fan_out.hpp"

#include <algorithm>
#include <chrono>
#include <limits>
#include <span>

#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel::pipeline {

void fan_out(const LabelingPlan& plan, const PointCloud& described, const LabelingOptions& options,
             PointCloud& cloud, LabelingResult& result, const CreaseAnswers* crease) {
  const auto start = std::chrono::steady_clock::now();
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  const std::vector<std::uint32_t>& slot_of = plan.slot_of;
  const std::size_t n = cloud.size();

  const std::uint32_t unknown = class_id(PrimitiveClass::kUnknown);
  std::vector<std::uint32_t> labels(n, unknown);
  std::size_t labeled = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (slot_of[i] != kNoSlot) {
      labels[i] = result.labels[slot_of[i]];
      labeled += labels[i] != unknown ? 1 : 0;
    }
  // A crease point's slot was labeled, and so is the point: the count stands.
  if (crease)
    for (std::size_t j = 0; j < crease->points.size(); ++j)
      labels[crease->points[j]] = crease->labels[j];
  result.labels = std::move(labels);
  // With one input point per slot the description's own count stands.
  if (plan.merges_points) result.labeled_points = labeled;

  if (options.want_probabilities) {
    Eigen::MatrixXf probabilities =
        Eigen::MatrixXf::Constant(Eigen::Index(n), Eigen::Index(result.class_ids.size()), kNaN);
    if (result.probabilities.size() > 0)
      for (std::size_t i = 0; i < n; ++i)
        if (slot_of[i] != kNoSlot)
          probabilities.row(Eigen::Index(i)) = result.probabilities.row(Eigen::Index(slot_of[i]));
    if (crease)
      for (std::size_t j = 0; j < crease->points.size(); ++j)
        probabilities.row(Eigen::Index(crease->points[j])) =
            crease->probabilities.row(Eigen::Index(j));
    result.probabilities = std::move(probabilities);
  } else {
    result.probabilities = {};  // the marginals the crease decision asked for
  }
  if (options.want_descriptors) {
    Descriptors descriptors = Descriptors::filled(n, result.descriptors.dim, kNaN);
    if (!result.descriptors.empty())
      for (std::size_t i = 0; i < n; ++i)
        if (slot_of[i] != kNoSlot) {
          const std::span<const float> row = result.descriptors.row(slot_of[i]);
          std::copy(row.begin(), row.end(), descriptors.row(i).begin());
        }
    result.descriptors = std::move(descriptors);
  }
  if (!options.use_cloud_normals) {
    cloud.normals.assign(n, Vec3f::Constant(kNaN));
    cloud.curvature.assign(n, kNaN);
    for (std::size_t i = 0; i < n; ++i)
      if (slot_of[i] != kNoSlot) {
        cloud.normals[i] = described.normals[slot_of[i]];
        cloud.curvature[i] = described.curvature[slot_of[i]];
      }
  }
  result.seconds.fanout +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace primlabel::pipeline
