#pragma once
// How one long call runs, as opposed to what it computes: the thread count, a stop token and a
// progress hook. Passed beside the persisted settings (crf::GraphSettings, InferenceSettings,
// FeatureSettings...) so that settings stay plain data that a model file can hold, and results
// never depend on anything in here.

#include <cstddef>
#include <stop_token>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/progress.hpp"

namespace primlabel {

struct RunContext {
  int threads = 0;  // 0 = OpenMP default; results do not depend on it
  // Checked per block of work; a stopped call skips what is left and throws Cancelled.
  // Braced defaults: RunContext{threads} then leaves them empty without a missing-initializer
  // warning.
  std::stop_token stop{};
  ProgressFn progress{};  // may be empty; called from one thread at a time

  bool stopped() const { return stop.stop_requested(); }
  // Throws Cancelled("<what> cancelled") once stopped.
  void throw_if_stopped(const char* what) const { primlabel::throw_if_stopped(stop, what); }
  void report(std::size_t done, std::size_t total) const {
    if (progress) progress(done, total);
  }
  // The same stop token and progress hook with another thread count (e.g. fewer for a small
  // problem).
  RunContext with_threads(int n) const { return {n, stop, progress}; }
};

}  // namespace primlabel
