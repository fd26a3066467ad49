// Multi-scale model input (FeatureSettings::extra_feature_radii, surface_variation_features):
// describe_cloud widens each row with the descriptor at the further radii and the surface
// variations; a model trained on it labels, returns clients the plain descriptor, is the same for
// 1 and 2 threads and survives its file; a file with impossible settings is refused.

#include <gtest/gtest.h>

#include <cmath>

#include "one_and_two_threads.hpp"
#include "primlabel/crf/metrics.hpp"
#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/normals.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/synth/generate.hpp"
#include "training_scenes.hpp"

namespace primlabel {
namespace {

FeatureSettings multi_scale_settings() {
  FeatureSettings features;
  features.extra_feature_radii = {0.015f, 0.04f};
  features.surface_variation_features = true;
  return features;
}

PointCloud test_scene() {
  return synth::synthetic_scene(synth::SceneSet::kTest, 1, synth::SensorKind::kLms400);
}

bool row_is_nan(std::span<const float> row) {
  for (float v : row)
    if (!std::isnan(v)) return false;
  return true;
}

TEST(PipelineMultiScale, RowsHoldEveryScaleThenTheVariations) {
  const FeatureSettings plain;
  const FeatureSettings wide = multi_scale_settings();
  ASSERT_EQ(wide.model_input_dim(), 3 * kFpfhSize + 4);
  PointCloud a = test_scene(), b = test_scene();
  const pipeline::DescribedCloud single = pipeline::describe_cloud(a, plain, RunContext{2});
  const pipeline::DescribedCloud multi = pipeline::describe_cloud(b, wide, RunContext{2});
  ASSERT_EQ(multi.descriptors.dim, wide.model_input_dim());
  ASSERT_EQ(multi.descriptors.size(), a.size());

  // The same cloud's FPFH at 15 mm, against the normals describe_cloud estimated.
  FeatureOptions small;
  small.neighborhood = pipeline::capped(Neighborhood::Radius(0.015f));
  small.fpfh_variant = plain.fpfh_variant;
  const Descriptors at_15mm = compute_fpfh(b, small, RunContext{2});
  // And its surface variation at 40 mm, from estimate_normals on a copy.
  PointCloud copy = b;
  NormalOptions wide_normals;
  wide_normals.neighborhood = pipeline::capped(Neighborhood::Radius(0.04f));
  estimate_normals(copy, wide_normals, RunContext{2});

  std::size_t valid = 0, bent = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto first = single.descriptors.row(i);
    const auto row = multi.descriptors.row(i);
    if (row_is_nan(first)) {
      EXPECT_TRUE(row_is_nan(row)) << i;
      continue;
    }
    ++valid;
    for (int j = 0; j < kFpfhSize; ++j) ASSERT_EQ(row[j], first[j]) << i << " bin " << j;
    // The same neighbours summed in another order (shared lists): equal up to rounding.
    for (int j = 0; j < kFpfhSize; ++j) {
      const float expected = std::isfinite(at_15mm.row(i)[j]) ? at_15mm.row(i)[j] : 0.0f;
      ASSERT_NEAR(row[kFpfhSize + j], expected, 1e-3f) << i << " bin " << j;
    }
    // Surface variation at 10, 25, 15 and 40 mm, scaled from [0, 1/3] to [0, 100].
    for (int v = 0; v < 4; ++v) {
      const float scaled = row[3 * kFpfhSize + v];
      ASSERT_GE(scaled, 0.0f);
      ASSERT_LE(scaled, 100.0f + 1e-3f);
    }
    // At the normal radius it is the curvature estimate_normals left in the cloud.
    ASSERT_EQ(row[3 * kFpfhSize], b.curvature[i] * 300.0f);
    const float at_40mm = std::isfinite(copy.curvature[i]) ? copy.curvature[i] * 300.0f : 0.0f;
    ASSERT_NEAR(row[3 * kFpfhSize + 3], at_40mm, 1e-3f) << i;
    bent += row[3 * kFpfhSize + 1] > 3.0f;  // variation above 0.01 at 25 mm: an edge or a curve
  }
  EXPECT_GT(valid, a.size() / 2);
  EXPECT_GT(bent, valid / 50) << "the scene's boxes and cylinders bend somewhere";
  EXPECT_LT(bent, valid) << "its table is flat";
}

TEST(PipelineMultiScale, TrainedModelLabelsGivesThePlainDescriptorAndRoundTrips) {
  const FeatureSettings features = multi_scale_settings();
  const crf::GraphSettings graph;
  const auto scenes = testing::prepare_training_scenes(
      testing::lms400_scenes(synth::SceneSet::kTrain, 2), {}, features, graph);
  pipeline::ModelTrainingOptions options;
  options.kind = ModelKind::kNodeOnly;
  options.iterations = 40;
  LabelModel model = testing::train_on(scenes, features, graph, options).model;
  ASSERT_EQ(model.weights.descriptor_dim, features.model_input_dim());
  // A CRF: the node weights and a coupling between neighbours, so the graph runs too.
  model.kind = ModelKind::kCrf;
  model.weights.edge_weights =
      Eigen::MatrixXf::Zero(model.weights.num_classes(), model.weights.edge_feature_dim());
  model.weights.edge_weights.col(model.weights.edge_feature_dim() - 1).setConstant(0.5f);

  const PointCloud truth = test_scene();
  pipeline::LabelingOptions labeling;
  labeling.want_descriptors = true;
  const auto [with_one, with_two] = testing::label_with_one_and_two_threads(model, truth, labeling);
  EXPECT_EQ(with_one.labels, with_two.labels);
  crf::ConfusionMatrix confusion(model.class_ids());
  confusion.add(truth.labels, with_two.labels, 0u);
  EXPECT_GT(confusion.accuracy(), 0.85);

  // Clients get the descriptor at the feature radius, as from a single-scale model.
  ASSERT_EQ(with_two.descriptors.dim, kFpfhSize);
  LabelModel single_scale;
  single_scale.kind = ModelKind::kNodeOnly;
  single_scale.weights = crf::CrfModel::zeros(model.class_ids(), kFpfhSize);
  PointCloud plain_cloud = truth;
  const auto plain = pipeline::label_cloud(single_scale, plain_cloud, labeling, RunContext{2});
  ASSERT_EQ(with_two.descriptors.size(), plain.descriptors.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < plain.descriptors.size(); ++i) {
    const auto a = with_two.descriptors.row(i), b = plain.descriptors.row(i);
    bool same = true;
    for (int j = 0; j < kFpfhSize; ++j)
      same = same && (a[j] == b[j] || (std::isnan(a[j]) && std::isnan(b[j])));
    if (!same && differing++ < 3)
      ADD_FAILURE() << "row " << i << ": " << a[0] << " " << a[1] << " vs " << b[0] << " " << b[1];
  }
  EXPECT_EQ(differing, 0u);

  const LabelModel loaded = parse_model(serialize_model(model), "round trip");
  EXPECT_EQ(loaded.features.extra_feature_radii, features.extra_feature_radii);
  EXPECT_TRUE(loaded.features.surface_variation_features);
  PointCloud again = truth;
  EXPECT_EQ(pipeline::label_cloud(loaded, again, {}, RunContext{2}).labels, with_two.labels);
}

TEST(PipelineMultiScale, ImpossibleSettingsInAFileAreRefused) {
  LabelModel model;
  model.kind = ModelKind::kNodeOnly;
  const auto refused = [&](FeatureSettings features, const std::string& reason) {
    model.features = features;
    model.weights = crf::CrfModel::zeros({1, 2}, features.model_input_dim());
    try {
      parse_model(serialize_model(model), "tampered.plm");
      ADD_FAILURE() << "accepted: " << reason;
    } catch (const ModelError& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("tampered.plm"), std::string::npos) << e.what();
    }
  };
  FeatureSettings negative = multi_scale_settings();
  negative.extra_feature_radii = {0.02f, -0.01f};
  refused(negative, "extra feature radius");
  FeatureSettings nan = multi_scale_settings();
  nan.extra_feature_radii = {std::nanf("")};
  refused(nan, "extra feature radius");
  FeatureSettings many = multi_scale_settings();
  many.extra_feature_radii = {0.01f, 0.02f, 0.03f, 0.04f, 0.05f};
  refused(many, "extra feature radii");
  FeatureSettings pfh = multi_scale_settings();
  pfh.descriptor = DescriptorKind::kPfh;
  refused(pfh, "need the FPFH descriptor");

  // The settings the tests above use are accepted.
  model.features = multi_scale_settings();
  model.weights = crf::CrfModel::zeros({1, 2}, model.features.model_input_dim());
  EXPECT_NO_THROW(parse_model(serialize_model(model), "fine.plm"));
}

}  // namespace
}  // namespace primlabel
