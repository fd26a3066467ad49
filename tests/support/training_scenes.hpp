#pragma once
// The steps test suites repeat to get a trained model: synthetic scenes described as
// primlabel-train describes them, labeled with the classes the training scenes hold, and a model
// trained on them. Needs primlabel::synth: only suites that link primlabel::research include it.

#include <cstdint>
#include <utility>
#include <vector>

#include "primlabel/pipeline/training.hpp"
#include "primlabel/synth/generate.hpp"

namespace primlabel::testing {

// Every taxonomy class id: scenes are described with all of them before the present ones are known.
inline std::vector<std::uint32_t> every_class_id() {
  std::vector<std::uint32_t> ids;
  for (PrimitiveClass c : all_classes()) ids.push_back(class_id(c));
  return ids;
}

// The first `count` synthetic LMS400 scenes of a set.
inline std::vector<PointCloud> lms400_scenes(synth::SceneSet set, int count) {
  std::vector<PointCloud> scenes;
  for (int i = 0; i < count; ++i)
    scenes.push_back(synth::synthetic_scene(set, i, synth::SensorKind::kLms400));
  return scenes;
}

struct TrainingScenes {
  std::vector<pipeline::SceneData> train, validation;
  std::vector<std::uint32_t> class_ids;  // present in `train`; every scene's labels follow them
};

inline TrainingScenes prepare_training_scenes(std::vector<PointCloud> train,
                                              std::vector<PointCloud> validation,
                                              const FeatureSettings& features,
                                              const crf::GraphSettings& graph) {
  const std::vector<std::uint32_t> every_class = every_class_id();
  TrainingScenes scenes;
  for (PointCloud& cloud : train)
    scenes.train.push_back(pipeline::prepare_scene(std::move(cloud), "train", features, graph,
                                                   every_class, RunContext{2}));
  for (PointCloud& cloud : validation)
    scenes.validation.push_back(pipeline::prepare_scene(std::move(cloud), "val", features, graph,
                                                        every_class, RunContext{2}));
  scenes.class_ids = pipeline::classes_present(scenes.train);
  for (pipeline::SceneData& s : scenes.train) pipeline::assign_labels(s, scenes.class_ids);
  for (pipeline::SceneData& s : scenes.validation) pipeline::assign_labels(s, scenes.class_ids);
  return scenes;
}

inline pipeline::ModelTrainingResult train_on(const TrainingScenes& scenes,
                                              const FeatureSettings& features,
                                              const crf::GraphSettings& graph,
                                              const pipeline::ModelTrainingOptions& options) {
  return pipeline::train_label_model(scenes.train, scenes.validation, scenes.class_ids, features,
                                     graph, options, RunContext{2});
}

}  // namespace primlabel::testing
