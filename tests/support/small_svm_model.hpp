#pragma once
// A real SVM model for tests that need one (the paper's baseline as a served model): libsvm RBF
// trained on 1,500 points of the first synthetic LMS400 training scene, in about a second.

#include "training_scenes.hpp"

namespace primlabel::testing {

inline LabelModel train_small_svm_model() {
  const FeatureSettings features;
  const crf::GraphSettings graph;
  const TrainingScenes scenes =
      prepare_training_scenes(lms400_scenes(synth::SceneSet::kTrain, 1), {}, features, graph);
  pipeline::ModelTrainingOptions options;
  options.kind = ModelKind::kSvm;
  options.svm.max_training_points = 1500;
  return train_on(scenes, features, graph, options).model;
}

}  // namespace primlabel::testing
