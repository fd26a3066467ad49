// The SVM baseline as a LabelModel: training into libsvm text, loading it back, labeling points.

#include "primlabel/pipeline/svm_model.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "multi_scale_input.hpp"
#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel::pipeline {

namespace {
double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

ModelTrainingResult train_svm_model(std::span<const SceneData> training,
                                    std::span<const SceneData> validation,
                                    const std::vector<std::uint32_t>& class_ids,
                                    const FeatureSettings& features,
                                    const crf::GraphSettings& graph, const svm::SvmOptions& options,
                                    const RunContext& context) {
  if (training.empty()) throw std::invalid_argument("no training scenes");
  std::vector<crf::LabeledGraph> graphs;
  graphs.reserve(training.size());
  for (const SceneData& s : training) graphs.push_back(s.graph);

  ModelTrainingResult out;
  const auto start = std::chrono::steady_clock::now();
  const svm::SvmClassifier svm = svm::SvmClassifier::train(graphs, class_ids, options);
  out.seconds = seconds_since(start);

  LabelModel& m = out.model;
  m.kind = ModelKind::kSvm;
  m.name = "svm";
  m.version = std::string("1");  // not = "1": GCC 12 warns falsely (-Wrestrict)
  m.features = features;
  m.graph = graph;  // unused by the SVM; kept so the file says how scenes were prepared
  m.svm_model = svm.to_libsvm_text();
  m.svm_class_ids = class_ids;
  m.weights.class_ids = class_ids;
  m.weights.descriptor_dim = features.model_input_dim();
  m.weights.feature_scale = svm.feature_scale();
  m.created_unix_ms = std::int64_t(std::time(nullptr)) * 1000;
  m.created_by = "primlabel-train";

  TrainingSummary& summary = m.training;
  summary = summarize_training(training, class_ids.size());
  char objective[160];
  std::snprintf(objective, sizeof objective,
                "svm rbf (C %g, gamma %.6g, %zu training points, %zu support vectors)", options.c,
                svm.gamma(), svm.training_points(), svm.support_vectors());
  summary.objective = objective;
  summary.seconds = out.seconds;
  if (!validation.empty()) m.validation = summarize(evaluate_scenes(m, validation, context));
  return out;
}

svm::SvmClassifier svm_classifier_of(const LabelModel& model) {
  if (model.kind != ModelKind::kSvm) throw ModelError(model.name + ": not an SVM model");
  try {
    return svm::SvmClassifier::from_libsvm_text(model.svm_model, model.svm_class_ids,
                                                model.features.model_input_dim(),
                                                model.weights.feature_scale);
  } catch (const std::invalid_argument& e) {
    throw ModelError(model.name + ": SVM model: " + e.what());
  }
}

void classify_with_svm(const LabelModel& model, DescribedCloud&& described,
                       const LabelingOptions& options, const RunContext& context,
                       LabelingResult& result) {
  const auto start = std::chrono::steady_clock::now();
  const svm::SvmClassifier svm = svm_classifier_of(model);
  svm::SvmPrediction predicted = svm.predict(
      described.descriptors, class_id(PrimitiveClass::kUnknown), context.threads, context.stop);
  result.class_ids = model.class_ids();
  result.labels = std::move(predicted.labels);
  if (options.want_probabilities) result.probabilities = std::move(predicted.probabilities);
  result.labeled_points = 0;
  for (std::size_t i = 0; i < described.descriptors.size(); ++i)
    result.labeled_points += std::isfinite(described.descriptors.row(i)[0]) ? 1 : 0;
  if (options.want_descriptors) {
    result.descriptors =
        leading_values(std::move(described.descriptors), model.features.descriptor_dim());
  }
  result.seconds.inference = seconds_since(start);
}

}  // namespace primlabel::pipeline
