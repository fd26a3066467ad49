#pragma once
// One load step against a server: closed loop (N callers, each sending its next cloud when the
// last one is answered) or open loop (calls issued at a fixed rate whatever the answers do, with
// latency measured from the scheduled send time, so a slow server cannot hide its queueing).
// A step ends after its duration or request count, and never runs longer than max_duration.
// Closed-loop callers back off after an admission rejection (LoadSpec::rejection_backoff).

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "load_stats.hpp"
#include "primlabel/client/backoff.hpp"
#include "primlabel/client/client.hpp"

namespace primlabel::client::loadgen {

enum class LoadMode { kClosed, kOpen };

struct LoadSpec {
  LoadMode mode = LoadMode::kClosed;
  int concurrency = 1;          // closed loop callers
  double rate = 10;             // open loop calls per second
  int max_outstanding = 256;    // open loop: calls in flight beyond this are skipped and counted
  double duration_s = 10;       // 0 = until `requests`
  std::uint64_t requests = 0;   // 0 = until `duration_s`
  double max_duration_s = 600;  // hard cap on a step
  bool unary = false;           // LabelCloud instead of the Label stream
  LabelOptions label;
  // Closed loop: a caller whose call was rejected at admission (RESOURCE_EXHAUSTED) waits this
  // backoff before its next call (reset by a success), so a full server is not flooded with
  // instant rejections. The open loop keeps its rate whatever the answers.
  BackoffPolicy rejection_backoff{std::chrono::milliseconds(50), 2.0,
                                  std::chrono::milliseconds(2000), 0.2};
};

struct StepResult {
  LoadSpec spec;
  double elapsed_s = 0;
  LoadStats stats;
};

// "START:END:STEP" (END and STEP optional) as perf_analyzer's --concurrency-range:
// START, START+STEP, ... up to END. Throws std::invalid_argument when malformed.
std::vector<int> parse_concurrency_range(const std::string& text);

StepResult run_step(Client& client, const std::vector<PointCloud>& clouds, const LoadSpec& spec);

}  // namespace primlabel::client::loadgen
