#pragma once
// The glue from a point cloud to per-point primitive labels: normals and descriptors with a
// model's feature settings, the CRF's neighbourhood graph, training scenes from labeled clouds,
// and labeling a cloud with a trained LabelModel.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "primlabel/core/neighbor_search.hpp"
#include "primlabel/core/point_cloud.hpp"
#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/training.hpp"
#include "primlabel/model/label_model.hpp"

namespace primlabel::pipeline {

// Normals (written into the cloud) and descriptors of every point, plus the neighbour index that
// computed them so the graph can reuse it. `search` indexes cloud.xyz: keep the cloud alive and
// unmoved while it is used.
struct DescribedCloud {
  std::vector<float> descriptors;  // row-major cloud.size() x descriptor_dim; NaN rows = invalid
  int descriptor_dim = 0;
  std::unique_ptr<NeighborSearch> search;
  double normal_seconds = 0, feature_seconds = 0;
};

// Throws std::invalid_argument for settings this build cannot honour (voxel downsampling).
DescribedCloud describe_cloud(PointCloud& cloud, const FeatureSettings& settings, int threads = 0);

crf::Graph build_scene_graph(const PointCloud& cloud, const DescribedCloud& described,
                             const crf::GraphOptions& options);

// A training / validation scene: labels become class indices into `class_ids`; taxonomy ids that
// are not one of the model's classes (kUnknown included) become kIgnoreLabel.
crf::LabeledGraph to_labeled_graph(const PointCloud& cloud, DescribedCloud&& described,
                                   crf::Graph graph, const std::vector<std::uint32_t>& class_ids);

struct LabelingOptions {
  int threads = 0;  // 0 = OpenMP default; the labels do not depend on it
  bool want_probabilities = false;
  bool tabletop_only = false;  // label only the table and the objects on it; the rest is unknown
};

struct LabelingResult {
  std::vector<std::uint32_t> labels;  // taxonomy class id per point; 0 (unknown) when unlabeled
  Eigen::MatrixXf probabilities;      // points x K (model class order) when asked; NaN rows
  std::vector<std::uint32_t> class_ids;
  std::size_t labeled_points = 0;  // points that had a descriptor
  double feature_seconds = 0;      // normals + descriptors
  double inference_seconds = 0;    // graph + inference
};

// Labels every point with the model's own feature, graph and inference settings. Points with
// non-finite coordinates or no descriptor get class 0. Throws ModelError when an SVM model's
// libsvm text does not load.
LabelingResult label_cloud(const LabelModel& model, PointCloud& cloud,
                           const LabelingOptions& options = {});

}  // namespace primlabel::pipeline
