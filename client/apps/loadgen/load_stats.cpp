#include "load_stats.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace primlabel::client::loadgen {

void LoadStats::record_ok(double latency_s, std::uint64_t points) {
  latencies_s_.push_back(latency_s);
  sorted_ = false;
  points_ += points;
}

void LoadStats::record_error(const std::string& status) { ++errors_[status]; }

void LoadStats::merge(const LoadStats& other) {
  latencies_s_.insert(latencies_s_.end(), other.latencies_s_.begin(), other.latencies_s_.end());
  sorted_ = false;
  for (const auto& [status, n] : other.errors_) errors_[status] += n;
  points_ += other.points_;
  skipped_ += other.skipped_;
}

std::uint64_t LoadStats::errors() const {
  std::uint64_t n = 0;
  for (const auto& [status, count] : errors_) n += count;
  return n;
}

std::uint64_t LoadStats::rejected() const {
  const auto it = errors_.find(kRejectedStatus);
  return it == errors_.end() ? 0 : it->second;
}

double LoadStats::percentile(double p) const {
  if (latencies_s_.empty()) return 0;
  if (!sorted_) {
    std::sort(latencies_s_.begin(), latencies_s_.end());
    sorted_ = true;
  }
  const double rank = std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * latencies_s_.size());
  const std::size_t index = rank < 1 ? 0 : static_cast<std::size_t>(rank) - 1;
  return latencies_s_[std::min(index, latencies_s_.size() - 1)];
}

double LoadStats::max() const {
  return latencies_s_.empty() ? 0 : *std::max_element(latencies_s_.begin(), latencies_s_.end());
}

double LoadStats::mean() const {
  if (latencies_s_.empty()) return 0;
  return std::accumulate(latencies_s_.begin(), latencies_s_.end(), 0.0) / latencies_s_.size();
}

}  // namespace primlabel::client::loadgen
