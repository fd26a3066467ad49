#pragma once
// Counts observations in buckets by upper bound (cumulative on collection), with their sum.

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace primlabel::metrics {

class Histogram {
 public:
  // Finite, strictly increasing upper bounds. The +Inf bucket is always added; a trailing +Inf
  // in the list is accepted and dropped. Throws std::invalid_argument otherwise.
  using BucketBoundaries = std::vector<double>;

  explicit Histogram(const BucketBoundaries& bounds);

  // Lock-free: one atomic bucket increment and one atomic add to the sum. NaN is ignored.
  void Observe(double v);

  struct Snapshot {
    std::vector<double> bounds;                    // finite bounds, then +Inf
    std::vector<std::uint64_t> cumulative_counts;  // one per bound: observations <= bound
    double sum;
    std::uint64_t count;  // == cumulative_counts.back()
  };
  Snapshot Collect() const;

  const std::vector<double>& bounds() const { return bounds_; }

 private:
  std::vector<double> bounds_;                                   // finite bounds only
  std::unique_ptr<std::atomic<std::uint64_t>[]> bucket_counts_;  // bounds_.size() + 1 (+Inf)
  std::atomic<double> sum_{0.0};
};

// Common bucket layouts.
// start, start*factor, ... (count bounds); e.g. exponential_buckets(0.001, 2, 12) for latencies.
Histogram::BucketBoundaries exponential_buckets(double start, double factor, int count);
// start, start+width, ... (count bounds).
Histogram::BucketBoundaries linear_buckets(double start, double width, int count);

}  // namespace primlabel::metrics
