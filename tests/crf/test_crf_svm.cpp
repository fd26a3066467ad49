#include <gtest/gtest.h>

#include <cmath>

#include "primlabel/crf/svm_baseline.hpp"
#include "synthetic.hpp"

namespace primlabel::crf {
namespace {

TEST(CrfSvm, LearnsASeparableProblem) {
  testing::SceneSpec spec;
  spec.width = 30;
  spec.height = 20;
  spec.num_classes = 3;
  spec.dim = 8;
  spec.noise = 5.0f;  // prototypes are ~100 apart: separable
  spec.seed = 1;
  const std::vector<LabeledGraph> train = {testing::make_grid_scene(spec)};
  spec.seed = 2;
  LabeledGraph test = testing::make_grid_scene(spec);
  test.descriptors[5 * spec.dim] = std::nanf("");

  SvmOptions options;
  options.max_training_points = 300;  // exercises the subsample
  const SvmClassifier svm = SvmClassifier::train(train, {11, 12, 13}, options);
  EXPECT_EQ(svm.training_points(), 300u);
  EXPECT_GT(svm.gamma(), 0.0);
  const SvmPrediction one = svm.predict(test.descriptors, 0, 1);
  const SvmPrediction two = svm.predict(test.descriptors, 0, 2);
  EXPECT_EQ(one.labels, two.labels);
  std::size_t correct = 0, counted = 0;
  for (std::size_t i = 0; i < test.labels.size(); ++i) {
    if (i == 5) {
      EXPECT_EQ(one.labels[i], 0u);
      EXPECT_TRUE(one.probabilities.row(i).array().isNaN().all());
      continue;
    }
    ++counted;
    correct += one.labels[i] == std::uint32_t(11 + test.labels[i]) ? 1 : 0;
    EXPECT_NEAR(one.probabilities.row(i).sum(), 1.0f, 1e-4f);
  }
  EXPECT_GT(double(correct) / counted, 0.98);
}

TEST(CrfSvm, RejectsEmptyTrainingData) {
  EXPECT_THROW(SvmClassifier::train({}, {1}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::crf
