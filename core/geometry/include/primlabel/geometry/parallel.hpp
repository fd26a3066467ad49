#pragma once
// The parallel loops: thread count resolution, an exception barrier (an exception leaving an
// OpenMP region calls std::terminate), the one parallel loop built on it (parallel_for) and its
// block form, and progress reporting that never calls the user's callback from two threads at
// once. Code outside this header writes no OpenMP pragma of its own.

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <optional>
#include <stop_token>
#include <vector>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/progress.hpp"
#include "primlabel/geometry/run_context.hpp"

namespace primlabel::detail {

inline int resolve_threads(int requested) {
  return requested > 0 ? requested : omp_get_max_threads();
}

// Keeps the first exception thrown inside an OpenMP region so that none escapes it. Wrap each
// thread's set-up and each iteration in run(); once one call has thrown, every later call on any
// thread returns at once (the others stop early), and rethrow() after the region throws it.
class ExceptionBarrier {
 public:
  template <typename F>
  void run(F&& f) noexcept {
    if (failed()) return;
    try {
      f();
    } catch (...) {
      if (!claimed_.exchange(true, std::memory_order_acq_rel)) error_ = std::current_exception();
      failed_.store(true, std::memory_order_release);
    }
  }
  bool failed() const noexcept { return failed_.load(std::memory_order_relaxed); }
  // Call after the region (its implicit barrier orders error_'s write before this read).
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::atomic<bool> failed_{false};
  std::atomic<bool> claimed_{false};
  std::exception_ptr error_;
};

// How a loop's iterations go to the threads: equal contiguous slices (static, the cheapest for
// uniform work) or chunks of `chunk` iterations on demand (dynamic, for uneven work).
struct Schedule {
  int chunk = 0;  // 0: static
  static constexpr Schedule Static() { return {0}; }
  static constexpr Schedule Dynamic(int chunk) { return {chunk}; }
};

// The one parallel loop of the code base (every other loop is built on it): body(scratch, i) for
// every i in [0, n) on `threads` threads (0 = OpenMP default), with one scratch per thread made
// by make_scratch(); after its last iteration each thread hands its scratch to merge(scratch),
// one thread at a time (for reductions: keep them order-independent, like a maximum, so that
// they do not depend on the thread count). No exception escapes the region: once make_scratch,
// body or merge has thrown, the remaining iterations are skipped and the first exception is
// rethrown here.
template <typename MakeScratch, typename Body, typename Merge>
void parallel_for(std::ptrdiff_t n, int threads, Schedule schedule, MakeScratch&& make_scratch,
                  Body&& body, Merge&& merge) {
  ExceptionBarrier barrier;
#pragma omp parallel num_threads(resolve_threads(threads))
  {
    std::optional<decltype(make_scratch())> scratch;
    barrier.run([&] { scratch.emplace(make_scratch()); });
    if (schedule.chunk <= 0) {
#pragma omp for schedule(static)
      for (std::ptrdiff_t i = 0; i < n; ++i)
        if (scratch) barrier.run([&] { body(*scratch, i); });
    } else {
#pragma omp for schedule(dynamic, schedule.chunk)
      for (std::ptrdiff_t i = 0; i < n; ++i)
        if (scratch) barrier.run([&] { body(*scratch, i); });
    }
    if (scratch) {
#pragma omp critical(primlabel_parallel_for_merge)
      barrier.run([&] { merge(*scratch); });
    }
  }
  barrier.rethrow();
}

template <typename MakeScratch, typename Body>
void parallel_for(std::ptrdiff_t n, int threads, Schedule schedule, MakeScratch&& make_scratch,
                  Body&& body) {
  parallel_for(n, threads, schedule, make_scratch, body, [](auto&) {});
}

// body(i) for every i in [0, n), without scratch.
template <typename Body>
void parallel_for(std::ptrdiff_t n, int threads, Schedule schedule, Body&& body) {
  struct None {};
  parallel_for(
      n, threads, schedule, [] { return None{}; }, [&](None&, std::ptrdiff_t i) { body(i); },
      [](None&) {});
}

// body(scratch, block) for every block in [0, blocks), one block at a time per thread (dynamic
// schedule), on context.threads threads, with one scratch per thread made by make_scratch(). The
// blocks are the caller's fixed unit of work, so what a block computes never depends on the
// thread count. Blocks are skipped once context.stop is requested (the caller then throws
// Cancelled) or once a block has thrown; the first exception is rethrown here, after the region.
template <typename MakeScratch, typename Body>
void for_each_block(std::ptrdiff_t blocks, const RunContext& context, MakeScratch&& make_scratch,
                    Body&& body) {
  const std::stop_token& stop = context.stop;
  parallel_for(blocks, context.threads, Schedule::Dynamic(1), make_scratch,
               [&](auto& scratch, std::ptrdiff_t block) {
                 if (!stop.stop_requested()) body(scratch, block);
               });
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
