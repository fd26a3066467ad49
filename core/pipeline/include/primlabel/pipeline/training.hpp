#pragma once
// From labeled clouds (synthetic scenes, files) to a trained LabelModel: scenes described with
// one set of feature settings, the model's classes, training, and validation figures.

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "primlabel/crf/metrics.hpp"
#include "primlabel/crf/training.hpp"
#include "primlabel/geometry/cloud_signature.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/model/svm_baseline.hpp"
#include "primlabel/pipeline/stage_seconds.hpp"

namespace primlabel::pipeline {

// One described scene: its graph, descriptors, and the ground truth as taxonomy ids.
struct SceneData {
  std::string source;
  crf::LabeledGraph graph;           // labels follow the class list of the last assign_labels
  std::vector<std::uint32_t> truth;  // taxonomy id per point
  StageSeconds seconds;              // its description's index, lists, normals and descriptors
  float point_spacing = 0;           // median point spacing as described (m; NaN: none)
  float surface_variation = 0;       // median surface variation of its normals (NaN: none)
  // The cloud's image size as acquired, before any voxel filter (0 x 0: unorganised).
  std::uint32_t image_width = 0, image_height = 0;
  // Its signature as acquired (cloud_signature.hpp); zeros when not measured.
  CloudSignature acquired;
};

// Describes a labeled cloud and builds its graph (labels are assigned with `class_ids`).
SceneData prepare_scene(PointCloud cloud, std::string source, const FeatureSettings& features,
                        const crf::GraphSettings& graph,
                        const std::vector<std::uint32_t>& class_ids,
                        const RunContext& context = {});

// Relabels the scene's graph for a class list (ids outside it are ignored).
void assign_labels(SceneData& scene, const std::vector<std::uint32_t>& class_ids);

// The taxonomy classes other than kUnknown that occur on described points of the scenes.
std::vector<std::uint32_t> classes_present(std::span<const SceneData> scenes);

struct ModelTrainingOptions {
  ModelKind kind = ModelKind::kCrf;
  crf::TrainingObjective objective = crf::TrainingObjective::kPiecewise;
  double l2 = 1e-6;
  int iterations = 200;
  // CRF and node-only: the tent basis of the node features (crf/model.hpp); empty = identity.
  std::vector<float> node_knots = crf::default_node_knots();
  // CRF and node-only: class balance alpha in [0, 1] (crf::class_balance_weights over the
  // training scenes' labelled points); 0 = the unweighted objective. Not for kSvm or Bethe.
  double class_balance = 0.0;
  // CRF: scale the learnt couplings down to what labels the validation scenes (or, without them,
  // the training scenes) best, as pseudo-likelihood overestimates them; and keep instead
  // node-only terms with a calibrated Potts coupling when that validates better (training.cpp).
  bool calibrate_edges = true;
  svm::SvmOptions svm;  // kSvm
  // Called per iteration with train / validation accuracy (slower: runs inference each time).
  std::function<void(const crf::TrainingIteration&)> on_iteration;
};

struct ModelTrainingResult {
  LabelModel model;
  crf::TrainingResult details;  // iterations, curve, why it stopped
  double seconds = 0;           // training and calibration (not features)
  float edge_scale = 1.0f;      // the calibrated coupling scale (CRF trained with PL)
  float potts_coupling = 0.0f;  // > 0 when node-only terms + a Potts coupling validated better
};

// Sources, scene and point counts, and labeled points per class of training scenes.
TrainingSummary summarize_training(std::span<const SceneData> training, std::size_t num_classes);

// Trains a CRF, node-only or SVM model; the scenes' labels must follow `class_ids`. Records the
// training summary and, when there are validation scenes, the validation metrics in the model.
ModelTrainingResult train_label_model(std::span<const SceneData> training,
                                      std::span<const SceneData> validation,
                                      const std::vector<std::uint32_t>& class_ids,
                                      const FeatureSettings& features,
                                      const crf::GraphSettings& graph,
                                      const ModelTrainingOptions& options,
                                      const RunContext& context = {});

// Predicted taxonomy ids for a described scene.
std::vector<std::uint32_t> predict_scene(const LabelModel& model, const SceneData& scene,
                                         const RunContext& context = {});

// Confusion of predictions against the scene truth over the model's classes (truth 0 skipped).
crf::ConfusionMatrix evaluate_scenes(const LabelModel& model, std::span<const SceneData> scenes,
                                     const RunContext& context = {});

EvaluationSummary summarize(const crf::ConfusionMatrix& confusion);

}  // namespace primlabel::pipeline
