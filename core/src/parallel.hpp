#pragma once
// Helpers for the OpenMP per-point loops: thread count resolution and progress reporting that
// never calls the user's callback from two threads at once.

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <stop_token>
#include <vector>

#include "primlabel/core/cancellation.hpp"
#include "primlabel/core/progress.hpp"

namespace primlabel::detail {

inline int resolve_threads(int requested) {
  return requested > 0 ? requested : omp_get_max_threads();
}

// v.assign(n, value), filled in slices of 1M elements with a stop check before each: the first
// touch of a 5M-point descriptor array (660 MB) takes ~0.3 s, too long to go unchecked.
template <typename T>
void assign_checked(std::vector<T>& v, std::size_t n, const T& value, const std::stop_token& stop,
                    const char* what) {
  constexpr std::size_t kSlice = std::size_t(1) << 20;
  v.clear();
  v.reserve(n);
  for (std::size_t done = 0; done < n; done = v.size()) {
    throw_if_stopped(stop, what);
    v.resize(std::min(n, done + kSlice), value);
  }
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
