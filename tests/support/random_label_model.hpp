#pragma once
// Small, fast fixtures for tests that need a model and a cloud but not a trained one: a model
// with seeded random weights (labels vary from point to point, so mix-ups show), an all-zero
// one, and a box-on-a-table cloud with planes, edges and corners.

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/model/label_model.hpp"

namespace primlabel::testing {

// A node-only (or, with coupling > 0, CRF) FPFH model over five classes, weights uniform in
// [-1, 1] from `seed`. Radii 1.5 cm / 3 cm suit table_with_box_cloud's 5 mm spacing.
inline LabelModel random_label_model(const std::string& name = "random",
                                     const std::string& version = "1", unsigned seed = 7,
                                     float coupling = 0.0f) {
  LabelModel model;
  model.name = name;
  model.version = version;
  model.kind = coupling > 0.0f ? ModelKind::kCrf : ModelKind::kNodeOnly;
  model.features.normals = Neighborhood::Radius(0.015f);
  model.features.features = Neighborhood::Radius(0.03f);
  model.weights = crf::CrfModel::zeros({1, 2, 4, 5, 6}, kFpfhSize);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  for (Eigen::Index r = 0; r < model.weights.node_weights.rows(); ++r)
    for (Eigen::Index c = 0; c < model.weights.node_weights.cols(); ++c)
      model.weights.node_weights(r, c) = uniform(rng);
  if (coupling > 0.0f)
    model.weights.edge_weights.col(model.weights.edge_feature_dim() - 1).setConstant(coupling);
  model.created_by = "random_label_model";
  return model;
}

// A node-only FPFH model over three classes with all-zero weights: loads and labels at once, every
// point the same class. `normals`, `features` > 0: those radii (small ones are fast on big frames).
inline LabelModel zero_node_model(float normals = 0.0f, float features = 0.0f) {
  LabelModel model;
  model.kind = ModelKind::kNodeOnly;
  model.weights = crf::CrfModel::zeros({1, 2, 4}, kFpfhSize);
  if (normals > 0.0f) model.features.normals = Neighborhood::Radius(normals);
  if (features > 0.0f) model.features.features = Neighborhood::Radius(features);
  return model;
}

// A 0.6 m square table top (z = 0) with a 0.2 m box standing on it, sampled every `spacing`
// metres, unorganised; the viewpoint is above.
inline PointCloud table_with_box_cloud(float spacing = 0.005f) {
  PointCloud cloud;
  std::vector<Vec3f> points;
  const int table_steps = int(std::lround(0.6f / spacing));
  for (int i = 0; i <= table_steps; ++i)
    for (int j = 0; j <= table_steps; ++j) {
      const float x = -0.3f + i * spacing, y = -0.3f + j * spacing;
      if (std::abs(x) < 0.1f && std::abs(y) < 0.1f) continue;  // under the box
      points.emplace_back(x, y, 0.0f);
    }
  const int box_steps = int(std::lround(0.2f / spacing));
  for (int i = 0; i <= box_steps; ++i)
    for (int j = 0; j <= box_steps; ++j) {
      const float u = -0.1f + i * spacing, v = j * spacing;
      points.emplace_back(u, -0.1f, v);  // four sides
      points.emplace_back(u, 0.1f, v);
      points.emplace_back(-0.1f, u, v);
      points.emplace_back(0.1f, u, v);
      points.emplace_back(u, -0.1f + j * spacing, 0.2f);  // top
    }
  cloud.resize_unorganized(points.size());
  cloud.xyz = std::move(points);
  cloud.viewpoint.origin = Vec3f(0.0f, 0.0f, 2.0f);
  return cloud;
}

}  // namespace primlabel::testing
