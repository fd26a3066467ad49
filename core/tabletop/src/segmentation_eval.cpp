#include "primlabel/tabletop/segmentation_eval.hpp"

#include <map>
#include <stdexcept>

namespace primlabel::tabletop {

namespace {

bool is_table_label(std::uint32_t label) { return label >= 1 && label <= 9; }
bool is_object_label(std::uint32_t label) { return label >= 20; }

}  // namespace

SegmentationScores evaluate_segmentation(const PointCloud& cloud, const TabletopResult& result) {
  if (!cloud.has_labels())
    throw std::invalid_argument("the cloud has no 'label' field to evaluate against");
  const std::size_t n = cloud.size();
  const std::vector<std::int32_t> predicted = segment_ids(result, n);
  SegmentationScores scores;

  std::size_t true_positive = 0, predicted_table = 0, true_table = 0;
  // Object id -> its valid point count, and (object, cluster) -> overlap.
  std::map<std::uint32_t, std::size_t> object_points;
  std::map<std::pair<std::uint32_t, std::int32_t>, std::size_t> overlap;
  std::vector<std::size_t> cluster_points(result.clusters.size(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!is_finite(cloud.xyz[i])) continue;
    const std::uint32_t label = cloud.labels[i];
    const std::int32_t segment = predicted[i];
    const bool table = segment == 0;
    predicted_table += table;
    true_table += is_table_label(label);
    true_positive += table && is_table_label(label);
    if (segment > 0) ++cluster_points[segment - 1];
    if (is_object_label(label)) {
      ++object_points[label / 10];
      if (segment > 0) ++overlap[{label / 10, segment - 1}];
    }
  }
  scores.table_precision = predicted_table ? double(true_positive) / double(predicted_table) : 0.0;
  scores.table_recall = true_table ? double(true_positive) / double(true_table) : 0.0;
  const double sum = scores.table_precision + scores.table_recall;
  scores.table_f1 = sum > 0 ? 2.0 * scores.table_precision * scores.table_recall / sum : 0.0;

  double iou_sum = 0.0;
  for (const auto& [object, points] : object_points) {
    ObjectScore score;
    score.object_id = object;
    score.points = points;
    for (auto it = overlap.lower_bound({object, 0});
         it != overlap.end() && it->first.first == object; ++it) {
      const std::int32_t cluster = it->first.second;
      const double iou = double(it->second) / double(points + cluster_points[cluster] - it->second);
      if (iou > score.best_iou) {
        score.best_iou = iou;
        score.best_cluster = cluster;
      }
    }
    iou_sum += score.best_iou;
    scores.objects.push_back(score);
  }
  scores.objects_true = object_points.size();
  scores.objects_found = result.clusters.size();
  scores.mean_object_iou = object_points.empty() ? 0.0 : iou_sum / double(object_points.size());
  return scores;
}

}  // namespace primlabel::tabletop
