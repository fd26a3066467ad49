#pragma once
// Synthetic labelled scenes for the CRF tests and `primlabel-bench crf`: points on a jittered grid
// whose labels form square regions (spatially smooth), with descriptors = a class prototype +
// Gaussian noise (so a node-only classifier makes clear mistakes that neighbours can correct).

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/model.hpp"
#include "primlabel/crf/training.hpp"

namespace primlabel::crf::testing {

struct SceneSpec {
  int width = 60;
  int height = 60;
  int num_classes = 3;
  int dim = 33;
  int region = 12;      // labels are constant on region x region squares
  float noise = 30.0f;  // std. dev. of the descriptor noise (prototype values are in [0, 100])
  std::uint32_t prototype_seed = 7;  // shared by train and test scenes: same classes
  std::uint32_t seed = 1;            // the noise and jitter of this scene
  int neighbors = 8;
};

inline std::vector<float> class_prototypes(int num_classes, int dim, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.0f, 100.0f);
  std::vector<float> prototypes(std::size_t(num_classes) * dim);
  for (float& v : prototypes) v = value(rng);
  return prototypes;
}

inline LabeledGraph make_grid_scene(const SceneSpec& spec,
                                    std::vector<Vec3f>* points_out = nullptr) {
  std::mt19937 rng(spec.seed);
  std::normal_distribution<float> noise(0.0f, spec.noise);
  std::uniform_real_distribution<float> jitter(-0.2f, 0.2f);
  const std::vector<float> prototypes =
      class_prototypes(spec.num_classes, spec.dim, spec.prototype_seed);
  const std::size_t n = std::size_t(spec.width) * spec.height;
  std::vector<Vec3f> points(n);
  LabeledGraph scene;
  scene.descriptors = Descriptors::filled(n, spec.dim, 0.0f);
  scene.labels.resize(n);
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      const std::size_t i = std::size_t(y) * spec.width + x;
      points[i] = Vec3f(x + jitter(rng), y + jitter(rng), 0.0f);
      const int label = (x / spec.region + 2 * (y / spec.region)) % spec.num_classes;
      scene.labels[i] = label;
      for (int f = 0; f < spec.dim; ++f)
        scene.descriptors.row(i)[f] =
            std::max(0.0f, prototypes[std::size_t(label) * spec.dim + f] + noise(rng));
    }
  }
  GraphSettings options;
  options.neighborhood = Neighborhood::Knn(spec.neighbors);
  scene.graph = build_graph(points, scene.descriptors, options);
  if (points_out) *points_out = std::move(points);
  return scene;
}

// A plausible model for the scene family: node weights point at the class prototypes, a positive
// edge bias rewards agreeing neighbours.
// A scene to train on and a held-out one of the same classes: `spec` with two noise seeds.
struct HeldOutScenes {
  LabeledGraph train, test;
};
inline HeldOutScenes held_out_scenes(SceneSpec spec, std::uint32_t train_seed,
                                     std::uint32_t test_seed) {
  HeldOutScenes scenes;
  spec.seed = train_seed;
  scenes.train = make_grid_scene(spec);
  spec.seed = test_seed;
  scenes.test = make_grid_scene(spec);
  return scenes;
}

inline CrfModel prototype_model(const SceneSpec& spec, float node_gain, float edge_bias) {
  std::vector<std::uint32_t> ids(spec.num_classes);
  for (int k = 0; k < spec.num_classes; ++k) ids[k] = static_cast<std::uint32_t>(k + 1);
  CrfModel model = CrfModel::zeros(ids, spec.dim);
  const std::vector<float> prototypes =
      class_prototypes(spec.num_classes, spec.dim, spec.prototype_seed);
  for (int k = 0; k < spec.num_classes; ++k) {
    float norm2 = 0.0f;
    for (int f = 0; f < spec.dim; ++f) {
      const float p = prototypes[std::size_t(k) * spec.dim + f] * model.feature_scale;
      model.node_weights(k, f) = node_gain * p;
      norm2 += p * p;
    }
    model.node_weights(k, spec.dim) = -0.5f * node_gain * norm2;  // nearest-prototype rule
    model.edge_weights(k, spec.dim) = edge_bias;
  }
  return model;
}

}  // namespace primlabel::crf::testing
