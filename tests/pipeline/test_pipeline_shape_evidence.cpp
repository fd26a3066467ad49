// Shape evidence (pipeline/shape_evidence.hpp): the table-top objects fitted with boxes and
// cylinders say what the taxonomy's rule gives their points, hidden faces included. On synthetic
// scenes, whose true labels come from the same rule on the true shapes, the evidence must mostly
// agree with them; it is the same for 1 and 2 threads; it is empty where there is nothing to fit;
// a model trained with it labels, survives its file, and older files read as models without it.
// (The noise-free box of random_label_model.hpp shows all four sides from above, which no sensor
// does and the box fitter, up to three faces, rightly refuses; the synthetic frames are the test.)

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "one_and_two_threads.hpp"
#include "primlabel/crf/metrics.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/pipeline/labeled_voxels.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/shape_evidence.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/synth/generate.hpp"
#include "random_label_model.hpp"
#include "training_scenes.hpp"

namespace primlabel {
namespace {

// A synthetic Kinect frame on the 7 mm voxels the depth model is served at.
PointCloud kinect_voxels(synth::SceneSet set, int index) {
  return pipeline::voxelize_labeled(synth::synthetic_scene(set, index, synth::SensorKind::kKinect),
                                    0.007f, RunContext{2});
}

struct Agreement {
  std::size_t points = 0, with_evidence = 0, agreeing = 0;
  std::size_t corners = 0, corners_found = 0;  // true corners, and those the evidence calls corner
};

Agreement agreement(const PointCloud& cloud, const std::vector<std::uint32_t>& evidence) {
  Agreement a;
  const std::uint32_t corner = class_id(PrimitiveClass::kCorner);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.labels[i] == 0) continue;
    ++a.points;
    if (evidence[i] != 0) ++a.with_evidence, a.agreeing += evidence[i] == cloud.labels[i];
    if (cloud.labels[i] == corner) ++a.corners, a.corners_found += evidence[i] == corner;
  }
  return a;
}

TEST(PipelineShapeEvidence, AgreesWithTheTrueLabelsOfSyntheticKinectFrames) {
  Agreement total;
  for (int index = 0; index < 2; ++index) {
    const PointCloud cloud = kinect_voxels(synth::SceneSet::kTest, index);
    const std::vector<std::uint32_t> one = pipeline::shape_evidence(cloud, RunContext{1});
    const std::vector<std::uint32_t> two = pipeline::shape_evidence(cloud, RunContext{2});
    ASSERT_EQ(one.size(), cloud.size());
    EXPECT_EQ(one, two) << "scene " << index;
    const Agreement a = agreement(cloud, two);
    total.points += a.points, total.with_evidence += a.with_evidence, total.agreeing += a.agreeing;
    total.corners += a.corners, total.corners_found += a.corners_found;
  }
  const double covered = double(total.with_evidence) / double(total.points);
  const double agreeing = double(total.agreeing) / double(total.with_evidence);
  const double corners = double(total.corners_found) / double(total.corners);
  std::printf(
      "shape evidence on %zu labeled voxels: covers %.3f, agrees %.3f, corners %.3f of %zu\n",
      total.points, covered, agreeing, corners, total.corners);
  EXPECT_GT(covered, 0.80) << "the table and most objects are fitted";
  EXPECT_GT(agreeing, 0.90) << "the fitted shapes are the true shapes, nearly";
  EXPECT_GT(corners, 0.50) << "hidden faces make corners a per-point model cannot see";
}

TEST(PipelineShapeEvidence, NothingToFitGivesNoEvidence) {
  PointCloud empty;
  EXPECT_TRUE(pipeline::shape_evidence(empty, RunContext{2}).empty());
  // Points scattered through a cube: no table, nothing to fit.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> uniform(-0.25f, 0.25f);
  std::vector<Vec3f> scattered(5000);
  for (Vec3f& p : scattered) p = Vec3f(uniform(rng), uniform(rng), 1.0f + uniform(rng));
  PointCloud cube;
  cube.resize_unorganized(scattered.size());
  cube.xyz = scattered;
  const auto evidence = pipeline::shape_evidence(cube, RunContext{2});
  EXPECT_EQ(std::count(evidence.begin(), evidence.end(), 0u), std::ptrdiff_t(cube.size()));
  // A NaN point amid a real scene has none.
  PointCloud scene = testing::table_with_box_cloud(0.01f);
  const auto clean = pipeline::shape_evidence(scene, RunContext{2});
  std::vector<Vec3f> points = scene.xyz;
  points.push_back(Vec3f::Constant(NAN));
  scene.resize_unorganized(points.size());
  scene.xyz = points;
  const auto with_nan = pipeline::shape_evidence(scene, RunContext{2});
  ASSERT_EQ(with_nan.size(), clean.size() + 1);
  EXPECT_EQ(with_nan.back(), 0u);
  // The fits sample other points then (RANSAC over the indices), so nearly the same evidence.
  std::size_t same = 0;
  for (std::size_t i = 0; i < clean.size(); ++i) same += clean[i] == with_nan[i];
  EXPECT_GT(same, clean.size() * 95 / 100);
}

TEST(PipelineShapeEvidence, ModelTrainedWithItLabelsAndRoundTrips) {
  FeatureSettings features;
  features.normals = Neighborhood::Radius(0.03f);
  features.features = Neighborhood::Radius(0.025f);
  features.shape_evidence = true;
  ASSERT_EQ(features.model_input_dim(), kFpfhSize + kShapeEvidenceDim);
  const crf::GraphSettings graph;
  std::vector<PointCloud> clouds;
  for (int i = 0; i < 2; ++i) clouds.push_back(kinect_voxels(synth::SceneSet::kTrain, i));
  const auto scenes = testing::prepare_training_scenes(std::move(clouds), {}, features, graph);
  ASSERT_EQ(scenes.train[0].graph.descriptors.dim, features.model_input_dim());
  pipeline::ModelTrainingOptions options;
  options.kind = ModelKind::kNodeOnly;
  options.iterations = 60;
  LabelModel model = testing::train_on(scenes, features, graph, options).model;
  model.features.voxel_size = 0.007f;
  ASSERT_EQ(model.weights.descriptor_dim, features.model_input_dim());
  ASSERT_TRUE(model.features.shape_evidence);

  const PointCloud frame =
      synth::synthetic_scene(synth::SceneSet::kTest, 0, synth::SensorKind::kKinect);
  pipeline::LabelingOptions labeling;
  labeling.want_descriptors = true;
  const auto [with_one, with_two] = testing::label_with_one_and_two_threads(model, frame, labeling);
  EXPECT_EQ(with_one.labels, with_two.labels);
  EXPECT_EQ(with_two.descriptors.dim, kFpfhSize) << "clients get the descriptor alone";
  crf::ConfusionMatrix confusion(model.class_ids());
  confusion.add(frame.labels, with_two.labels, 0u);
  EXPECT_GT(confusion.accuracy(), 0.85);

  const LabelModel loaded = parse_model(serialize_model(model), "round trip");
  EXPECT_TRUE(loaded.features.shape_evidence);
  PointCloud again = frame;
  EXPECT_EQ(pipeline::label_cloud(loaded, again, {}, RunContext{2}).labels, with_two.labels);

  // A model file from before shape evidence reads as a model without it.
  LabelModel older = model;
  older.features.shape_evidence = false;
  older.weights = crf::CrfModel::zeros(model.class_ids(), kFpfhSize);
  EXPECT_FALSE(parse_model(serialize_model(older), "older").features.shape_evidence);
}

TEST(PipelineShapeEvidence, WeightsThatMissTheEvidenceAreRefused) {
  LabelModel model = testing::random_label_model();
  model.features.shape_evidence = true;  // weights still for the descriptor alone
  try {
    serialize_model(model);
    ADD_FAILURE() << "accepted";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("features give 43"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace primlabel
