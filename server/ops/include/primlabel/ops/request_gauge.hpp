#pragma once
// The labeling requests in progress (from an accepted header to their end, whatever their
// phase) and those waiting for a worker, reported to the metrics together so the two gauges
// never show a stale pair.

#include <mutex>

#include "primlabel/ops/server_metrics.hpp"

namespace primlabel::ops {

class RequestGauge {
 public:
  explicit RequestGauge(ServerMetrics& metrics) : metrics_(metrics) {}

  void add_in_flight(int delta) {
    std::lock_guard lock(mutex_);
    in_flight_ += delta;
    metrics_.set_admission(in_flight_, queued_);
  }
  void set_queued(int queued) {
    std::lock_guard lock(mutex_);
    queued_ = queued;
    metrics_.set_admission(in_flight_, queued_);
  }
  int in_flight() const {
    std::lock_guard lock(mutex_);
    return in_flight_;
  }

 private:
  ServerMetrics& metrics_;
  mutable std::mutex mutex_;
  int in_flight_ = 0, queued_ = 0;
};

}  // namespace primlabel::ops
