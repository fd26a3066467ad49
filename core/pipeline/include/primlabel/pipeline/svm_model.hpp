#pragma once
// The SVM baseline as a LabelModel: trained on described scenes like the CRF, stored as libsvm's
// text model in the model file, and applied point by point (no graph).

#include <span>
#include <vector>

#include "primlabel/model/svm_baseline.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/training.hpp"

namespace primlabel::pipeline {

// Trains the RBF-SVM on the scenes (labels following `class_ids`) into a model of kind kSvm with
// its training summary and, when there are validation scenes, validation metrics.
ModelTrainingResult train_svm_model(std::span<const SceneData> training,
                                    std::span<const SceneData> validation,
                                    const std::vector<std::uint32_t>& class_ids,
                                    const FeatureSettings& features,
                                    const crf::GraphSettings& graph, const svm::SvmOptions& options,
                                    const RunContext& context = {});

// The classifier in an SVM model; throws ModelError when its libsvm text does not load.
svm::SvmClassifier svm_classifier_of(const LabelModel& model);

// Labels described points with an SVM model into `result`: labels, probabilities and descriptors
// when asked, labeled points and inference time (the feature fields are left alone).
void classify_with_svm(const LabelModel& model, DescribedCloud&& described,
                       const LabelingOptions& options, const RunContext& context,
                       LabelingResult& result);

}  // namespace primlabel::pipeline
