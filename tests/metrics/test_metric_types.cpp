// Counter, gauge, histogram, family and registry semantics.

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "primlabel/metrics/metrics.hpp"

namespace primlabel::metrics {
namespace {

TEST(Counter, StartsAtZeroAndOnlyGoesUp) {
  Counter counter;
  EXPECT_EQ(counter.Value(), 0.0);
  counter.Increment();
  counter.Increment(2.5);
  counter.Increment(-10);  // ignored, as in prometheus-cpp
  counter.Increment(NAN);  // ignored
  EXPECT_EQ(counter.Value(), 3.5);
}

TEST(Gauge, IncrementsDecrementsAndSets) {
  Gauge gauge;
  gauge.Increment();
  gauge.Increment(4);
  gauge.Decrement(2);
  EXPECT_EQ(gauge.Value(), 3.0);
  gauge.Decrement();
  EXPECT_EQ(gauge.Value(), 2.0);
  gauge.Set(-7.25);
  EXPECT_EQ(gauge.Value(), -7.25);
}

TEST(Histogram, BucketsAreInclusiveAndCumulativeWithInf) {
  Histogram histogram({1, 2, 4});
  for (double v : {0.5, 1.0, 1.5, 2.0, 3.0, 100.0}) histogram.Observe(v);
  histogram.Observe(NAN);  // ignored
  const auto snapshot = histogram.Collect();
  ASSERT_EQ(snapshot.bounds.size(), 4u);
  EXPECT_EQ(snapshot.bounds.back(), INFINITY);
  EXPECT_EQ(snapshot.cumulative_counts, (std::vector<std::uint64_t>{2, 4, 5, 6}));
  EXPECT_EQ(snapshot.count, 6u);
  EXPECT_EQ(snapshot.sum, 108.0);
}

TEST(Histogram, AcceptsTrailingInfAndRejectsBadBounds) {
  EXPECT_EQ(Histogram({1, INFINITY}).bounds(), (std::vector<double>{1}));
  EXPECT_EQ(Histogram({}).Collect().bounds.size(), 1u);  // only +Inf
  EXPECT_THROW(Histogram({2, 1}), std::invalid_argument);
  EXPECT_THROW(Histogram({1, 1}), std::invalid_argument);
  EXPECT_THROW(Histogram({NAN}), std::invalid_argument);
  EXPECT_THROW(Histogram({-INFINITY, 1}), std::invalid_argument);
}

TEST(Histogram, BucketHelpers) {
  EXPECT_EQ(exponential_buckets(0.001, 10, 3), (std::vector<double>{0.001, 0.01, 0.001 * 10 * 10}));
  EXPECT_EQ(linear_buckets(1, 0.5, 3), (std::vector<double>{1, 1.5, 2}));
  EXPECT_THROW(exponential_buckets(0, 2, 3), std::invalid_argument);
  EXPECT_THROW(linear_buckets(0, 1, 0), std::invalid_argument);
}

TEST(Family, SameLabelsGiveTheSameMetric) {
  Registry registry;
  auto& family = BuildCounter().Name("x_total").Help("x").Register(registry);
  Counter& a = family.Add({{"method", "Label"}});
  Counter& b = family.Add({{"method", "Label"}});
  Counter& c = family.Add({{"method", "Admin"}});
  EXPECT_EQ(&a, &b);
  EXPECT_NE(&a, &c);
}

TEST(Family, RemoveDropsTheSeries) {
  Registry registry;
  auto& family = BuildGauge().Name("g").Help("g").Register(registry);
  family.Add({{"model", "a"}}).Set(1);
  Gauge& b = family.Add({{"model", "b"}});
  b.Set(2);
  family.Remove(&b);
  Gauge unrelated;
  family.Remove(&unrelated);  // ignored
  const std::string text = registry.Serialize();
  EXPECT_NE(text.find("g{model=\"a\"} 1"), std::string::npos) << text;
  EXPECT_EQ(text.find("model=\"b\""), std::string::npos) << text;
}

TEST(Family, HistogramBucketsMustAgreeForTheSameLabels) {
  Registry registry;
  auto& family = BuildHistogram().Name("h_seconds").Help("h").Register(registry);
  Histogram& h = family.Add({{"stage", "fpfh"}}, {1, 2});
  EXPECT_EQ(&family.Add({{"stage", "fpfh"}}, {1, 2}), &h);
  EXPECT_THROW(family.Add({{"stage", "fpfh"}}, {1, 3}), std::invalid_argument);
  EXPECT_THROW(family.Add({{"le", "1"}}, {1}), std::invalid_argument);
}

TEST(Names, MetricAndLabelNamesAreValidated) {
  EXPECT_TRUE(is_valid_metric_name("primlabel_requests_total"));
  EXPECT_TRUE(is_valid_metric_name("job:rate5m"));
  EXPECT_FALSE(is_valid_metric_name(""));
  EXPECT_FALSE(is_valid_metric_name("1abc"));
  EXPECT_FALSE(is_valid_metric_name("a-b"));
  EXPECT_FALSE(is_valid_metric_name("a b"));
  EXPECT_TRUE(is_valid_label_name("_x9"));
  EXPECT_FALSE(is_valid_label_name("__name__"));
  EXPECT_FALSE(is_valid_label_name("a:b"));
  EXPECT_FALSE(is_valid_label_name("9a"));

  Registry registry;
  EXPECT_THROW(BuildCounter().Name("bad-name").Register(registry), std::invalid_argument);
  EXPECT_THROW(BuildCounter().Name("c").Labels({{"bad label", "v"}}).Register(registry),
               std::invalid_argument);
  auto& family = BuildCounter().Name("ok_total").Labels({{"service", "p"}}).Register(registry);
  EXPECT_THROW(family.Add({{"bad-label", "v"}}), std::invalid_argument);
  EXPECT_THROW(family.Add({{"service", "again"}}), std::invalid_argument);  // repeats a constant
}

TEST(Registry, ReRegisteringReturnsTheSameFamilyOrThrows) {
  Registry registry;
  auto& first = BuildCounter().Name("r_total").Help("r").Register(registry);
  EXPECT_EQ(&BuildCounter().Name("r_total").Help("r").Register(registry), &first);
  EXPECT_THROW(BuildGauge().Name("r_total").Register(registry), std::invalid_argument);
  EXPECT_THROW(BuildCounter().Name("r_total").Labels({{"a", "b"}}).Register(registry),
               std::invalid_argument);
}

TEST(Registry, HistogramSeriesNamesCannotBeReused) {
  Registry registry;
  BuildHistogram().Name("lat_seconds").Register(registry);
  EXPECT_THROW(BuildCounter().Name("lat_seconds_count").Register(registry), std::invalid_argument);
  BuildGauge().Name("depth_sum").Register(registry);
  EXPECT_THROW(BuildHistogram().Name("depth").Register(registry), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::metrics
