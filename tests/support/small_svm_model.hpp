#pragma once
// A real SVM model for tests that need one (the paper's baseline as a served model): libsvm RBF
// trained on 1,500 points of the first synthetic LMS400 training scene, in about a second.

#include <cstdint>
#include <vector>

#include "primlabel/pipeline/training.hpp"
#include "primlabel/synth/generate.hpp"

namespace primlabel::testing {

inline LabelModel train_small_svm_model() {
  const FeatureSettings features;
  const crf::GraphSettings graph;
  std::vector<std::uint32_t> every_class;
  for (PrimitiveClass c : all_classes()) every_class.push_back(class_id(c));
  std::vector<pipeline::SceneData> train;
  train.push_back(pipeline::prepare_scene(
      synth::synthetic_scene(synth::SceneSet::kTrain, 0, synth::SensorKind::kLms400), "train",
      features, graph, every_class, RunContext{2}));
  const auto class_ids = pipeline::classes_present(train);
  pipeline::assign_labels(train.front(), class_ids);
  pipeline::ModelTrainingOptions options;
  options.kind = ModelKind::kSvm;
  options.svm.max_training_points = 1500;
  return pipeline::train_label_model(train, {}, class_ids, features, graph, options, RunContext{2})
      .model;
}

}  // namespace primlabel::testing
