#pragma once
// Scores a table-top segmentation against mOSD-style ground truth labels: 0 invalid, 1-9 table
// (parts), 10k..10k+9 (k >= 2) parts of object k. Only points with finite coordinates count.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/tabletop/tabletop.hpp"

namespace primlabel::tabletop {

struct ObjectScore {
  std::uint32_t object_id = 0;  // label / 10
  std::size_t points = 0;       // valid ground-truth points
  double best_iou = 0.0;        // best IoU over the clusters
  int best_cluster = -1;        // index into clusters, -1 when no cluster overlaps
};

struct SegmentationScores {
  double table_precision = 0, table_recall = 0, table_f1 = 0;
  double mean_object_iou = 0;  // over ground-truth objects; 0 when there are none
  std::size_t objects_found = 0, objects_true = 0;
  std::vector<ObjectScore> objects;
};

// Ground truth from cloud.labels (throws std::invalid_argument when the cloud has none).
SegmentationScores evaluate_segmentation(const PointCloud& cloud, const TabletopResult& result);

}  // namespace primlabel::tabletop
