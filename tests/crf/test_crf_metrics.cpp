#include <gtest/gtest.h>

#include <cmath>

#include "primlabel/crf/metrics.hpp"

namespace primlabel::crf {
namespace {

TEST(CrfMetrics, ConfusionMatrixScores) {
  ConfusionMatrix m({1, 2, 3});
  // truth 1: 3 right, 1 as 2; truth 2: 2 right, 1 as unknown (0); truth 3: never occurs.
  const std::vector<std::uint32_t> truth = {1, 1, 1, 1, 2, 2, 2, 0};
  const std::vector<std::uint32_t> predicted = {1, 1, 1, 2, 2, 2, 0, 1};
  m.add(truth, predicted, /*ignore_truth=*/0u);
  EXPECT_EQ(m.total(), 7u);
  EXPECT_EQ(m.skipped(), 1u);
  EXPECT_EQ(m.count(0, 0), 3u);
  EXPECT_EQ(m.count(0, 1), 1u);
  EXPECT_EQ(m.count(1, 3), 1u);  // "other" column
  EXPECT_NEAR(m.accuracy(), 5.0 / 7.0, 1e-12);
  const ClassScores s1 = m.scores(0);
  EXPECT_NEAR(s1.precision, 1.0, 1e-12);
  EXPECT_NEAR(s1.recall, 0.75, 1e-12);
  EXPECT_NEAR(s1.f1, 2 * 0.75 / 1.75, 1e-12);
  const ClassScores s2 = m.scores(1);
  EXPECT_NEAR(s2.precision, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(s2.recall, 2.0 / 3.0, 1e-12);
  EXPECT_TRUE(std::isnan(m.scores(2).recall));
  EXPECT_NEAR(m.macro_f1(), (s1.f1 + s2.f1) / 2, 1e-12);
  const std::string text = m.to_text({"plane", "edge", "corner"});
  EXPECT_NE(text.find("plane"), std::string::npos);
  EXPECT_NE(text.find("other"), std::string::npos);
  EXPECT_NE(text.find("accuracy 0.714"), std::string::npos);
}

TEST(CrfMetrics, EmptyMatrix) {
  ConfusionMatrix m({4});
  EXPECT_TRUE(std::isnan(m.accuracy()));
  EXPECT_TRUE(std::isnan(m.macro_f1()));
  EXPECT_THROW(ConfusionMatrix({}), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::crf
