#pragma once
// A monotonically increasing value, e.g. requests served.

#include <atomic>

namespace primlabel::metrics {

// The hot path must never take a lock.
static_assert(std::atomic<double>::is_always_lock_free);

class Counter {
 public:
  // Adds v. Like prometheus-cpp, a negative or NaN v is ignored: a counter never goes down, and
  // a metric must never take the request that reports it down with it.
  void Increment(double v = 1.0) {
    if (!(v >= 0.0)) return;
    value_.fetch_add(v, std::memory_order_relaxed);
  }
  double Value() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<double> value_{0.0};
};

}  // namespace primlabel::metrics
