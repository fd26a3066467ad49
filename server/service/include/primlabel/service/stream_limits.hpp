#pragma once
// The rules a streamed labeling call lives by besides its deadline, without a transport: the
// order of its messages (a ScanHeader, then PointChunks, then an EndOfScan or the half-close),
// a message at least every --stream-idle-seconds while the scan comes in, at least
// --min-receive-bytes-per-second over every --receive-rate-window-seconds (after a grace window),
// and every answer message taken within --send-timeout-seconds. The RPC edge reports what happens
// and keeps one timer at next_check().

#include <chrono>
#include <cstdint>
#include <optional>

#include "primlabel/ops/server_config.hpp"
#include "primlabel/service/service_error.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::service {

enum class StreamPhase { kHeader, kReceiving, kLabeling, kSending, kFinished };

// What the call is doing in `phase`, for error messages ("receiving points").
const char* doing(StreamPhase phase);

// INVALID_ARGUMENT when message `index` (from 1) cannot come in `phase` (kHeader or kReceiving).
std::optional<ServiceError> out_of_order(StreamPhase phase, const v1::LabelRequest& request,
                                         std::uint64_t index);

class StreamLimits {
 public:
  using Clock = std::chrono::steady_clock;

  StreamLimits(const ops::ServerConfig& config, Clock::time_point now);

  void message_arrived(std::uint64_t bytes, Clock::time_point now);
  // The header was accepted: the first rate window begins after a grace period of one window.
  void receiving_started(Clock::time_point now);
  void write_started(Clock::time_point now);
  void write_done() { write_pending_ = false; }
  bool write_pending() const { return write_pending_; }

  // The next moment a limit could be reached in `phase`; Clock::time_point::max() for none.
  Clock::time_point next_check(StreamPhase phase) const;
  // The limit `phase` has broken by `now`, if any; a rate window that passed starts the next.
  std::optional<ServiceError> check(StreamPhase phase, Clock::time_point now);

 private:
  const ops::ServerConfig& config_;
  Clock::time_point last_message_;
  Clock::time_point window_start_, rate_check_at_;
  std::uint64_t window_bytes_ = 0;
  bool write_pending_ = false;
  Clock::time_point write_started_;
};

}  // namespace primlabel::service
