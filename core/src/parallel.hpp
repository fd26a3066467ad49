#pragma once
// Helpers for the OpenMP per-point loops: thread count resolution and progress reporting that
// never calls the user's callback from two threads at once.

#include <omp.h>

#include <atomic>
#include <cstddef>

#include "primlabel/core/progress.hpp"

namespace primlabel::detail {

inline int resolve_threads(int requested) {
  return requested > 0 ? requested : omp_get_max_threads();
}

// Counts finished points; the OpenMP master thread forwards the count to the callback every
// `stride` points it sees, so the callback runs on one thread only.
class ProgressCounter {
 public:
  ProgressCounter(const ProgressFn& fn, std::size_t total) : fn_(fn), total_(total) {}
  void add(std::size_t n) {
    const std::size_t done = done_.fetch_add(n, std::memory_order_relaxed) + n;
    if (fn_ && omp_get_thread_num() == 0 && done - last_reported_ >= stride_) {
      last_reported_ = done;
      fn_(done, total_);
    }
  }
  void finish() {
    if (fn_) fn_(total_, total_);
  }

 private:
  const ProgressFn& fn_;
  std::size_t total_;
  std::atomic<std::size_t> done_{0};
  std::size_t last_reported_ = 0;  // touched by thread 0 only
  std::size_t stride_ = 4096;
};

}  // namespace primlabel::detail
