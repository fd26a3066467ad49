// Scenes for training and evaluation, and training a LabelModel from them.

#include "primlabel/pipeline/training.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <set>
#include <stdexcept>

#include "primlabel/crf/inference.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/svm_model.hpp"

namespace primlabel::pipeline {

namespace {
double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<crf::LabeledGraph> graphs_of(std::span<const SceneData> scenes) {
  std::vector<crf::LabeledGraph> out;
  out.reserve(scenes.size());
  for (const SceneData& s : scenes) out.push_back(s.graph);
  return out;
}

struct Calibration {
  float value;      // the chosen scale or coupling
  double accuracy;  // on the calibration scenes
};

// Pseudo-likelihood conditions on the true labels of the neighbours, so it overestimates how
// strongly neighbours agree: run with loopy BP, the learnt couplings flood whole scenes with one
// label. The couplings are therefore scaled down by the factor (from a short grid) that labels
// the calibration scenes best.
Calibration calibrate_edge_scale(LabelModel& model, std::span<const SceneData> scenes,
                                 const RunContext& context) {
  static constexpr float kScales[] = {1.0f, 0.3f, 0.1f, 0.03f};
  const Eigen::MatrixXf learnt = model.weights.edge_weights;
  float best_scale = 1.0f;
  double best_accuracy = -1.0;
  for (float scale : kScales) {
    model.weights.edge_weights = learnt * scale;
    const double accuracy = evaluate_scenes(model, scenes, context).accuracy();
    if (accuracy > best_accuracy) best_accuracy = accuracy, best_scale = scale;
  }
  model.weights.edge_weights = learnt * best_scale;
  return {best_scale, best_accuracy};
}

// Node terms plus a uniform associative coupling beta (edge bias) for every class, beta picked
// from a short grid on the calibration scenes.
Calibration calibrate_potts_coupling(LabelModel& model, std::span<const SceneData> scenes,
                                     const RunContext& context) {
  static constexpr float kCouplings[] = {0.0f, 0.05f, 0.1f, 0.25f, 1.0f};
  crf::CrfModel& w = model.weights;
  float best_coupling = 0.0f;
  double best_accuracy = -1.0;
  for (float beta : kCouplings) {
    w.edge_weights = Eigen::MatrixXf::Zero(w.num_classes(), w.edge_feature_dim());
    w.edge_weights.col(w.edge_feature_dim() - 1).setConstant(beta);
    const double accuracy = evaluate_scenes(model, scenes, context).accuracy();
    if (accuracy > best_accuracy) best_accuracy = accuracy, best_coupling = beta;
  }
  w.edge_weights = Eigen::MatrixXf::Zero(w.num_classes(), w.edge_feature_dim());
  w.edge_weights.col(w.edge_feature_dim() - 1).setConstant(best_coupling);
  return {best_coupling, best_accuracy};
}

const char* objective_name(ModelKind kind, crf::TrainingObjective objective) {
  if (kind == ModelKind::kNodeOnly) return "node-only";
  switch (objective) {
    case crf::TrainingObjective::kBetheBp:
      return "bethe";
    case crf::TrainingObjective::kPseudoLikelihood:
      return "pseudo-likelihood";
    default:
      return "piecewise";
  }
}
}  // namespace

SceneData prepare_scene(PointCloud cloud, std::string source, const FeatureSettings& features,
                        const crf::GraphSettings& graph,
                        const std::vector<std::uint32_t>& class_ids, const RunContext& context) {
  SceneData scene;
  scene.source = std::move(source);
  if (cloud.organized()) scene.image_width = cloud.width, scene.image_height = cloud.height;
  DescribedCloud described = describe_cloud(cloud, features, context);
  scene.seconds = described.seconds;
  scene.point_spacing = described.point_spacing;
  scene.surface_variation = described.surface_variation;
  crf::Graph g = build_scene_graph(cloud, described, graph, context);
  scene.graph = to_labeled_graph(cloud, std::move(described), std::move(g), class_ids);
  scene.truth = std::move(cloud.labels);
  return scene;
}

void assign_labels(SceneData& scene, const std::vector<std::uint32_t>& class_ids) {
  auto& labels = scene.graph.labels;
  labels.assign(scene.truth.size(), crf::kIgnoreLabel);
  for (std::size_t i = 0; i < scene.truth.size(); ++i) {
    if (!scene.graph.graph.active[i]) continue;
    for (std::size_t k = 0; k < class_ids.size(); ++k)
      if (class_ids[k] == scene.truth[i]) labels[i] = static_cast<int>(k);
  }
}

std::vector<std::uint32_t> classes_present(std::span<const SceneData> scenes) {
  std::set<std::uint32_t> ids;
  for (const SceneData& s : scenes)
    for (std::size_t i = 0; i < s.truth.size(); ++i)
      if (s.graph.graph.active[i] && s.truth[i] != class_id(PrimitiveClass::kUnknown))
        ids.insert(s.truth[i]);
  return {ids.begin(), ids.end()};
}

std::vector<std::uint32_t> predict_scene(const LabelModel& model, const SceneData& scene,
                                         const RunContext& context) {
  if (model.kind == ModelKind::kSvm)
    return svm_classifier_of(model)
        .predict(scene.graph.descriptors, class_id(PrimitiveClass::kUnknown), context.threads,
                 context.stop)
        .labels;
  crf::InferenceOutputs outputs;
  outputs.unknown_label = class_id(PrimitiveClass::kUnknown);
  return crf::infer(model.weights, scene.graph.descriptors, scene.graph.graph, model.inference,
                    outputs, context)
      .labels;
}

crf::ConfusionMatrix evaluate_scenes(const LabelModel& model, std::span<const SceneData> scenes,
                                     const RunContext& context) {
  crf::ConfusionMatrix confusion(model.class_ids());
  for (const SceneData& s : scenes)
    confusion.add(s.truth, predict_scene(model, s, context), class_id(PrimitiveClass::kUnknown));
  return confusion;
}

EvaluationSummary summarize(const crf::ConfusionMatrix& confusion) {
  EvaluationSummary summary;
  summary.points = confusion.total();
  summary.accuracy = confusion.accuracy();
  for (int k = 0; k < confusion.num_classes(); ++k) {
    const crf::ClassScores s = confusion.scores(k);
    summary.per_class.push_back({s.precision, s.recall, s.f1, s.support});
  }
  return summary;
}

TrainingSummary summarize_training(std::span<const SceneData> training, std::size_t num_classes) {
  TrainingSummary summary;
  for (const SceneData& s : training) {
    summary.sources.push_back(s.source);
    summary.points += s.truth.size();
  }
  summary.scenes = training.size();
  for (const SceneData& s : training) {
    if (!(s.point_spacing > 0.0f)) continue;  // NaN: no distinct points
    summary.point_spacing_min = summary.point_spacing_min > 0.0f
                                    ? std::min(summary.point_spacing_min, s.point_spacing)
                                    : s.point_spacing;
    summary.point_spacing_max = std::max(summary.point_spacing_max, s.point_spacing);
  }
  // The least and greatest of a positive figure over the scenes (NaN and 0: not measured).
  const auto widen = [](float value, float& low, float& high) {
    if (!(value > 0.0f) || !std::isfinite(value)) return;
    low = low > 0.0f ? std::min(low, value) : value;
    high = std::max(high, value);
  };
  for (const SceneData& s : training) {
    // Surface variation is at most 1/3, so widen's finite check changes nothing for it.
    widen(s.surface_variation, summary.surface_variation_min, summary.surface_variation_max);
    widen(s.acquired.point_spacing, summary.acquired_spacing_min, summary.acquired_spacing_max);
    widen(s.acquired.roughness, summary.roughness_min, summary.roughness_max);
    // The growth may be 0 or below: NaN alone means not measured.
    if (std::isfinite(s.acquired.noise_growth)) {
      const float g = s.acquired.noise_growth;
      const bool first = !std::isfinite(summary.noise_growth_min);
      summary.noise_growth_min = first ? g : std::min(summary.noise_growth_min, g);
      summary.noise_growth_max = first ? g : std::max(summary.noise_growth_max, g);
    }
    if (std::isfinite(s.acquired.depth_ties)) {
      const float ties = s.acquired.depth_ties;
      const bool first = !std::isfinite(summary.depth_ties_min);
      summary.depth_ties_min = first ? ties : std::min(summary.depth_ties_min, ties);
      summary.depth_ties_max = first ? ties : std::max(summary.depth_ties_max, ties);
    }
  }
  // An image size only when every scene was a frame of that one size.
  if (!training.empty() && training.front().image_height > 1 &&
      std::all_of(training.begin(), training.end(), [&](const SceneData& s) {
        return s.image_width == training.front().image_width &&
               s.image_height == training.front().image_height;
      })) {
    summary.image_width = training.front().image_width;
    summary.image_height = training.front().image_height;
  }
  summary.class_points.assign(num_classes, 0);
  for (const SceneData& s : training)
    for (int label : s.graph.labels)
      if (label >= 0) ++summary.class_points[std::size_t(label)];
  return summary;
}

ModelTrainingResult train_label_model(std::span<const SceneData> training,
                                      std::span<const SceneData> validation,
                                      const std::vector<std::uint32_t>& class_ids,
                                      const FeatureSettings& features,
                                      const crf::GraphSettings& graph,
                                      const ModelTrainingOptions& options,
                                      const RunContext& context) {
  if (!(options.class_balance >= 0.0 && options.class_balance <= 1.0))
    throw std::invalid_argument("class balance must be in [0, 1]");
  if (options.kind == ModelKind::kSvm) {
    if (options.class_balance > 0.0)
      throw std::invalid_argument("class balance applies to CRF and node-only models, not svm");
    return train_svm_model(training, validation, class_ids, features, graph, options.svm, context);
  }
  if (training.empty()) throw std::invalid_argument("no training scenes");
  const std::vector<crf::LabeledGraph> train_graphs = graphs_of(training);
  const std::vector<crf::LabeledGraph> val_graphs = graphs_of(validation);

  crf::TrainingOptions training_options;
  training_options.objective =
      options.kind == ModelKind::kNodeOnly ? crf::TrainingObjective::kNodeOnly : options.objective;
  training_options.l2 = options.l2;
  training_options.max_iterations = options.iterations;
  training_options.node_knots = options.node_knots;
  training_options.on_iteration = options.on_iteration;
  const TrainingSummary counted = summarize_training(training, class_ids.size());
  if (options.class_balance > 0.0)
    training_options.class_weights =
        crf::class_balance_weights(counted.class_points, options.class_balance);

  ModelTrainingResult out;
  const auto start = std::chrono::steady_clock::now();
  out.details = crf::train_crf(train_graphs, val_graphs, class_ids, training_options, context);
  out.seconds = seconds_since(start);

  LabelModel& m = out.model;
  m.name = options.kind == ModelKind::kNodeOnly ? "node-only" : "crf";
  m.version = "1";
  m.kind = options.kind;
  m.features = features;
  m.graph = graph;
  m.weights = out.details.model;
  m.inference = training_options.inference;
  m.created_unix_ms = std::int64_t(std::time(nullptr)) * 1000;
  m.created_by = "primlabel-train";

  TrainingSummary& summary = m.training;
  summary = counted;
  summary.class_balance = options.class_balance;
  summary.class_weights = training_options.class_weights;
  summary.objective = objective_name(options.kind, options.objective);
  summary.l2 = options.l2;
  summary.iterations = std::uint32_t(out.details.iterations);
  summary.seconds = out.seconds;

  const std::span<const SceneData> calibration = validation.empty() ? training : validation;
  if (options.kind == ModelKind::kCrf &&
      training_options.objective == crf::TrainingObjective::kPiecewise) {
    // Node factors trained alone; the coupling is the one edge factor, chosen on validation.
    // With one uniform coupling, mean-field labels like loopy BP at a fraction of its time
    // (docs/development.md, "Figures behind the code"), so such models infer with it.
    m.inference.method = crf::InferenceMethod::kMeanField;
    const Calibration coupling = calibrate_potts_coupling(m, calibration, context);
    out.potts_coupling = coupling.value;
    out.edge_scale = 0.0f;
    summary.objective = "piecewise: node-only + Potts coupling " + std::to_string(coupling.value);
  } else if (options.kind == ModelKind::kCrf && options.calibrate_edges) {
    const Calibration pl = calibrate_edge_scale(m, calibration, context);
    out.edge_scale = pl.value;
    // The alternative: node terms trained alone plus one Potts coupling for every class.
    crf::TrainingOptions node_options = training_options;
    node_options.objective = crf::TrainingObjective::kNodeOnly;
    node_options.on_iteration = nullptr;
    LabelModel potts = m;
    potts.weights = crf::train_crf(train_graphs, {}, class_ids, node_options, context).model;
    const Calibration coupling = calibrate_potts_coupling(potts, calibration, context);
    out.potts_coupling = coupling.value;
    if (coupling.accuracy > pl.accuracy) {
      m.weights = potts.weights;
      summary.objective = "node-only + Potts coupling " + std::to_string(out.potts_coupling);
      out.edge_scale = 0.0f;
    } else {
      out.potts_coupling = 0.0f;
      summary.objective += " (edge scale " + std::to_string(out.edge_scale) + ")";
    }
  }
  out.seconds = seconds_since(start);
  summary.seconds = out.seconds;
  if (!validation.empty()) m.validation = summarize(evaluate_scenes(m, validation, context));
  return out;
}

}  // namespace primlabel::pipeline
