// SVM models end to end: trained into a LabelModel, applied by label_cloud, identical after a
// round trip through the model file, and refused with a ModelError when the libsvm text is broken.

#include <gtest/gtest.h>

#include <algorithm>

#include "primlabel/crf/metrics.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/svm_model.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/synth/generate.hpp"
#include "small_svm_model.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

// A strip of a held-out LMS400 scene (its first sweep lines): small enough to label quickly.
PointCloud small_scene() {
  PointCloud scene = synth::synthetic_scene(synth::SceneSet::kTest, 0, synth::SensorKind::kLms400);
  const std::size_t keep = 20000;
  scene.xyz.resize(keep);
  scene.labels.resize(keep);
  scene.width = std::uint32_t(keep);
  scene.height = 1;
  return scene;
}

using testing::train_small_svm_model;

// Equal element by element, NaN where the other is NaN.
bool identical(const Eigen::MatrixXf& a, const Eigen::MatrixXf& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return false;
  return ((a.array() == b.array()) || (a.array().isNaN() && b.array().isNaN())).all();
}

// One case, so the training runs once per process.
TEST(PipelineSvm, TrainedSvmLabelsASceneIdenticallyAfterAFileRoundTrip) {
  const LabelModel model = train_small_svm_model();
  EXPECT_EQ(model.kind, ModelKind::kSvm);
  EXPECT_NE(model.training.objective.find("svm rbf"), std::string::npos);
  const PointCloud scene = small_scene();

  PointCloud cloud = scene;
  pipeline::LabelingOptions options;
  options.want_probabilities = true;
  const RunContext context{2};
  const pipeline::LabelingResult before = pipeline::label_cloud(model, cloud, options, context);
  ASSERT_EQ(before.labels.size(), scene.size());
  EXPECT_GT(before.labeled_points, scene.size() / 2);
  crf::ConfusionMatrix confusion(model.class_ids());
  confusion.add(scene.labels, before.labels, 0u);
  EXPECT_GT(confusion.accuracy(), 0.75);
  ASSERT_EQ(before.probabilities.cols(), Eigen::Index(model.class_ids().size()));

  test::TempDir dir;
  save_model(dir.file("svm.plm"), model);
  const LabelModel loaded = load_model(dir.file("svm.plm"));
  EXPECT_EQ(loaded.kind, ModelKind::kSvm);
  EXPECT_EQ(loaded.class_ids(), model.class_ids());
  EXPECT_EQ(loaded.weights.feature_scale, model.weights.feature_scale);
  EXPECT_EQ(pipeline::svm_classifier_of(loaded).gamma(),
            pipeline::svm_classifier_of(model).gamma());
  PointCloud again = scene;
  const pipeline::LabelingResult after = pipeline::label_cloud(loaded, again, options, context);
  EXPECT_EQ(after.labels, before.labels);
  EXPECT_TRUE(identical(after.probabilities, before.probabilities));

  // Broken libsvm text: refused when the file is written, read, or applied.
  LabelModel broken = loaded;
  broken.svm_model = broken.svm_model.substr(0, broken.svm_model.size() / 2);
  try {
    pipeline::label_cloud(broken, again, options, context);
    FAIL() << "labeled with a truncated SVM";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("SVM model: libsvm model, line"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  EXPECT_THROW(serialize_model(broken), ModelError);
  LabelModel wrong_dim = loaded;
  wrong_dim.features.descriptor = DescriptorKind::kPfh;  // the SVM's indices still fit 125 bins
  wrong_dim.svm_class_ids.resize(1);                     // but its labels no longer fit
  try {
    serialize_model(wrong_dim);
    FAIL() << "accepted an SVM whose labels exceed its classes";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("is not one of the 1 classes"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace primlabel
