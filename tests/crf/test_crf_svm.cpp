#include <gtest/gtest.h>
#include <libsvm/svm.h>

#include <cmath>
#include <fstream>
#include <stop_token>

#include "crf_scenes.hpp"
#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/model/svm_baseline.hpp"
#include "test_util.hpp"

namespace primlabel::crf {
using svm::SvmClassifier;
using svm::SvmOptions;
using svm::SvmPrediction;

namespace {

TEST(CrfSvm, LearnsASeparableProblem) {
  testing::SceneSpec spec;
  spec.width = 30;
  spec.height = 20;
  spec.num_classes = 3;
  spec.dim = 8;
  spec.noise = 5.0f;  // prototypes are ~100 apart: separable
  auto [train_scene, test] = testing::held_out_scenes(spec, 1, 2);
  const std::vector<LabeledGraph> train = {std::move(train_scene)};
  test.descriptors.row(5)[0] = std::nanf("");

  SvmOptions options;
  options.max_training_points = 300;  // exercises the subsample
  const SvmClassifier svm = SvmClassifier::train(train, {11, 12, 13}, options);
  EXPECT_EQ(svm.training_points(), 300u);
  EXPECT_GT(svm.gamma(), 0.0);
  // Typed descriptors must have the classifier's dimension.
  EXPECT_THROW(svm.predict(Descriptors(spec.dim + 1, {}), 0, 1), std::invalid_argument);
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

// Overlapping classes, so probabilities and decisions depend on every digit of the model.
struct NoisyProblem {
  testing::SceneSpec spec;
  LabeledGraph test;
  SvmClassifier svm;
};

NoisyProblem noisy_problem() {
  testing::SceneSpec spec;
  spec.width = 24;
  spec.height = 16;
  spec.num_classes = 3;
  spec.dim = 8;
  spec.noise = 40.0f;
  auto [train_scene, test] = testing::held_out_scenes(spec, 3, 4);
  const std::vector<LabeledGraph> train = {std::move(train_scene)};
  SvmOptions options;
  options.max_training_points = 200;
  return {spec, std::move(test), SvmClassifier::train(train, {11, 12, 13}, options)};
}

TEST(CrfSvm, LibsvmTextRoundTripPredictsIdentically) {
  const NoisyProblem p = noisy_problem();
  const std::string text = p.svm.to_libsvm_text();
  ASSERT_EQ(text.rfind("svm_type c_svc\nkernel_type rbf\ngamma ", 0), 0u) << text.substr(0, 80);
  const SvmClassifier back = SvmClassifier::from_libsvm_text(text, {11, 12, 13}, p.spec.dim, 0.01f);
  EXPECT_EQ(back.to_libsvm_text(), text);
  EXPECT_EQ(back.gamma(), p.svm.gamma());
  EXPECT_EQ(back.support_vectors(), p.svm.support_vectors());
  EXPECT_TRUE(back.has_probabilities());
  const SvmPrediction before = p.svm.predict(p.test.descriptors, 0, 2);
  const SvmPrediction after = back.predict(p.test.descriptors, 0, 2);
  EXPECT_EQ(before.labels, after.labels);
  EXPECT_TRUE(before.probabilities == after.probabilities);
  // Not trivially separable: the round trip is tested on uncertain points too.
  EXPECT_LT(before.probabilities.rowwise().maxCoeff().minCoeff(), 0.9f);
}

TEST(CrfSvm, AStopRequestCancelsPrediction) {
  const NoisyProblem p = noisy_problem();
  std::stop_source never;
  const SvmPrediction plain = p.svm.predict(p.test.descriptors, 0, 2);
  EXPECT_EQ(p.svm.predict(p.test.descriptors, 0, 2, never.get_token()).labels, plain.labels);
  std::stop_source stopped;
  stopped.request_stop();
  try {
    p.svm.predict(p.test.descriptors, 0, 2, stopped.get_token());
    FAIL() << "a stopped prediction returned labels";
  } catch (const Cancelled& e) {
    EXPECT_STREQ(e.what(), "SVM prediction cancelled");
  }
}

TEST(CrfSvm, LibsvmReadsOurTextAndWeReadLibsvms) {
  const NoisyProblem p = noisy_problem();
  test::TempDir dir;
  const std::string ours = dir.file("ours.model"), theirs = dir.file("theirs.model");
  std::ofstream(ours) << p.svm.to_libsvm_text();
  svm_model* loaded = svm_load_model(ours.c_str());
  ASSERT_NE(loaded, nullptr);
  ASSERT_EQ(svm_save_model(theirs.c_str(), loaded), 0);
  // libsvm's own labels are class indices; compare with ours on every test point.
  const SvmPrediction ours_predicted = p.svm.predict(p.test.descriptors, 0, 1);
  std::vector<svm_node> row;
  std::vector<double> estimates(3);
  for (std::size_t i = 0; i < p.test.labels.size(); ++i) {
    row.clear();
    for (int f = 0; f < p.spec.dim; ++f) {
      const float v = p.test.descriptors.row(i)[f];
      if (v != 0.0f) row.push_back({f + 1, 0.01 * v});
    }
    row.push_back({-1, 0.0});
    EXPECT_EQ(11 + int(svm_predict_probability(loaded, row.data(), estimates.data())),
              int(ours_predicted.labels[i]))
        << i;
  }
  svm_free_and_destroy_model(&loaded);

  // libsvm's file (support vectors with 8 digits) reads back and labels (almost) alike.
  std::ifstream in(theirs);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const SvmClassifier back = SvmClassifier::from_libsvm_text(text, {11, 12, 13}, p.spec.dim, 0.01f);
  const SvmPrediction theirs_predicted = back.predict(p.test.descriptors, 0, 1);
  std::size_t same = 0;
  for (std::size_t i = 0; i < p.test.labels.size(); ++i)
    same += theirs_predicted.labels[i] == ours_predicted.labels[i];
  EXPECT_GE(double(same) / double(p.test.labels.size()), 0.99);
}

std::string parse_error(const std::string& text, int classes = 3, int dim = 8) {
  std::vector<std::uint32_t> ids;
  for (int k = 0; k < classes; ++k) ids.push_back(std::uint32_t(11 + k));
  try {
    SvmClassifier::from_libsvm_text(text, ids, dim, 0.01f);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// A valid header for `classes` classes claiming `total_sv` support vectors (all of the last
// class), and no support vectors.
std::string many_classes_header(int classes, int total_sv) {
  std::string text = "svm_type c_svc\nkernel_type rbf\ngamma 1\nnr_class " +
                     std::to_string(classes) + "\ntotal_sv " + std::to_string(total_sv) + "\nrho";
  for (int p = 0; p < classes * (classes - 1) / 2; ++p) text += " 0";
  text += "\nlabel";
  for (int k = 0; k < classes; ++k) text += " " + std::to_string(k);
  text += "\nnr_sv";
  for (int k = 0; k < classes; ++k) text += " " + std::to_string(k + 1 == classes ? total_sv : 0);
  return text + "\nSV\n";
}

TEST(CrfSvm, CorruptLibsvmTextIsRejectedWithTheReason) {
  const std::string good = noisy_problem().svm.to_libsvm_text();
  const struct {
    std::string text, reason;
    int classes = 3, dim = 8;
  } cases[] = {
      {"", "no SV section"},
      {"hello world\n", "line 1: unknown header entry 'hello'"},
      {good.substr(0, good.size() / 2), "support vectors (truncated?)"},
      {good.substr(0, good.find("SV\n")), "no SV section"},
      {replaced(good, "kernel_type rbf", "kernel_type linear"), "line 2: kernel_type must be rbf"},
      {replaced(good, "svm_type c_svc", "svm_type one_class"), "line 1: svm_type must be c_svc"},
      {replaced(good, "gamma ", "gamma x"), "line 3: gamma 'x"},
      {replaced(good, "nr_class 3", "nr_class 99999999"), "nr_class '99999999' is not an integer"},
      {replaced(good, "nr_sv ", "nr_sv 1 "), "nr_sv has 4 values, expected 3"},
      {replaced(good, "label 0", "label 1"), "labels repeat"},
      {replaced(good, "\nSV\n", "\nSV\n1 2 9:0.5\n"),
       "feature index '9' is not an integer in 1..8"},
      {replaced(good, "\nSV\n", "\nSV\n1 2 3:0.5 2:0.5\n"), "feature indices must increase"},
      {replaced(good, "\nSV\n", "\nSV\n1 2 3:nan\n"), "feature value 'nan' is not a finite"},
      {replaced(good, "\nSV\n", "\nSV\n1 2 3:0.5\n"), "more support vectors than total_sv"},
      {good, "label 2 is not one of the 2 classes", 2},
      {many_classes_header(200, 20000), "total_sv 20000 is more than the text holds"},
      {good + "\n", "(accepted)"},
  };
  for (const auto& c : cases) {
    const std::string error = parse_error(c.text, c.classes, c.dim);
    EXPECT_NE(error.find(c.reason), std::string::npos)
        << "expected: " << c.reason << "\ngot: " << error;
  }
}

TEST(CrfSvm, TruncatedTextIsRefusedUpToTheLastLine) {
  // The text has no checksum (the model file has): a cut inside the last support vector's line
  // can leave a valid, shorter line. Any earlier cut loses a line and is refused.
  const std::string good = noisy_problem().svm.to_libsvm_text();
  const std::size_t last_line = good.rfind('\n', good.size() - 2) + 1;
  for (std::size_t cut = 0; cut < good.size(); cut += 7) {
    try {
      SvmClassifier::from_libsvm_text(good.substr(0, cut), {11, 12, 13}, 8, 0.01f);
      EXPECT_GT(cut, last_line) << "accepted a cut at " << cut;
    } catch (const std::invalid_argument&) {
    }
  }
}

TEST(CrfSvm, RejectsEmptyTrainingData) {
  EXPECT_THROW(SvmClassifier::train({}, {1}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::crf
