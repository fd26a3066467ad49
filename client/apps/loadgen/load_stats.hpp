#pragma once
// What one load step measured: latencies of successful calls, errors by status (admission
// rejections apart), points labeled, and the summary figures (throughput, percentiles).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace primlabel::client::loadgen {

// The status of an admission rejection, as status_code_name spells it.
inline constexpr const char* kRejectedStatus = "RESOURCE_EXHAUSTED";

class LoadStats {
 public:
  void record_ok(double latency_s, std::uint64_t points);
  void record_error(const std::string& status);
  void record_skipped() { ++skipped_; }  // open loop: the client had too many calls in flight
  void merge(const LoadStats& other);

  std::uint64_t ok() const { return latencies_s_.size(); }
  std::uint64_t errors() const;  // every failed call, rejections included
  // Calls the server turned away at admission (RESOURCE_EXHAUSTED: its workers and queue were
  // full): a figure of the load, not a failure of the server.
  std::uint64_t rejected() const;
  std::uint64_t failed() const { return errors() - rejected(); }  // the other errors
  std::uint64_t skipped() const { return skipped_; }
  std::uint64_t points() const { return points_; }
  const std::map<std::string, std::uint64_t>& errors_by_status() const { return errors_; }

  // Latency at percentile p in [0, 100] (nearest rank), in seconds; 0 when nothing succeeded.
  double percentile(double p) const;
  double max() const;
  double mean() const;

 private:
  mutable std::vector<double> latencies_s_;
  mutable bool sorted_ = true;
  std::map<std::string, std::uint64_t> errors_;
  std::uint64_t points_ = 0;
  std::uint64_t skipped_ = 0;
};

}  // namespace primlabel::client::loadgen
