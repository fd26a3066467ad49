// Many threads updating and creating metrics while others serialise: totals must be exact.

#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "primlabel/metrics/metrics.hpp"

namespace primlabel::metrics {
namespace {

constexpr int kThreads = 8;
constexpr int kIterations = 50000;

TEST(Concurrency, CounterGaugeAndHistogramTotalsAreExact) {
  Registry registry;
  auto& counters = BuildCounter().Name("c_total").Register(registry);
  auto& gauges = BuildGauge().Name("g").Register(registry);
  auto& histograms = BuildHistogram().Name("h").Register(registry);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < kIterations; ++i) {
        // Families are looked up on every iteration, as a server does per request.
        counters.Add({{"shared", "yes"}}).Increment();
        counters.Add({{"thread", std::to_string(t)}}).Increment(2);
        Gauge& inflight = gauges.Add({});
        inflight.Increment();
        inflight.Decrement();
        histograms.Add({}, {0.5}).Observe(i % 2 == 0 ? 0.25 : 1.0);
      }
    });
  }
  // A scraper serialising concurrently must see well-formed, monotone snapshots.
  double last_shared = 0;
  for (int scrape = 0; scrape < 20; ++scrape) {
    std::vector<Sample> samples;
    EXPECT_NO_THROW(samples = parse_exposition(registry.Serialize()));
    const double shared = sum_samples(samples, "c_total", {{"shared", "yes"}});
    EXPECT_GE(shared, last_shared);
    last_shared = shared;
    EXPECT_EQ(sum_samples(samples, "h_count"), sum_samples(samples, "h_bucket", {{"le", "+Inf"}}));
  }
  for (auto& thread : threads) thread.join();

  EXPECT_EQ(counters.Add({{"shared", "yes"}}).Value(), kThreads * kIterations);
  for (int t = 0; t < kThreads; ++t)
    EXPECT_EQ(counters.Add({{"thread", std::to_string(t)}}).Value(), 2.0 * kIterations);
  EXPECT_EQ(gauges.Add({}).Value(), 0.0);
  const auto snapshot = histograms.Add({}, {0.5}).Collect();
  EXPECT_EQ(snapshot.count, std::uint64_t{kThreads} * kIterations);
  EXPECT_EQ(snapshot.cumulative_counts[0], std::uint64_t{kThreads} * kIterations / 2);
  EXPECT_EQ(snapshot.sum, kThreads * (kIterations / 2) * 1.25);
}

TEST(Concurrency, RegisteringTheSameFamilyFromManyThreadsYieldsOneFamily) {
  Registry registry;
  std::vector<Family<Counter>*> seen(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back(
        [&, t] { seen[t] = &BuildCounter().Name("once_total").Register(registry); });
  for (auto& thread : threads) thread.join();
  for (auto* family : seen) EXPECT_EQ(family, seen[0]);
  EXPECT_EQ(registry.Collect().size(), 1u);
}

}  // namespace
}  // namespace primlabel::metrics
