#include "primlabel/service/stream_limits.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

namespace primlabel::service {

namespace {

using Clock = StreamLimits::Clock;

Clock::duration seconds(double value) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(value));
}

double seconds_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

const char* kind_name(v1::LabelRequest::KindCase kind) {
  switch (kind) {
    case v1::LabelRequest::kHeader:
      return "a ScanHeader";
    case v1::LabelRequest::kChunk:
      return "a PointChunk";
    case v1::LabelRequest::kEnd:
      return "an EndOfScan";
    default:
      return "an empty LabelRequest";
  }
}

bool receiving(StreamPhase phase) {
  return phase == StreamPhase::kHeader || phase == StreamPhase::kReceiving;
}

}  // namespace

const char* doing(StreamPhase phase) {
  switch (phase) {
    case StreamPhase::kHeader:
      return "waiting for the ScanHeader";
    case StreamPhase::kReceiving:
      return "receiving points";
    case StreamPhase::kLabeling:
      return "labeling";
    default:
      return "sending labels";
  }
}

std::optional<ServiceError> out_of_order(StreamPhase phase, const v1::LabelRequest& request,
                                         std::uint64_t index) {
  if (phase == StreamPhase::kHeader) {
    if (request.has_header()) return std::nullopt;
    return ServiceError{
        ErrorCode::kInvalidArgument,
        std::string("message 1 must be a ScanHeader, got ") + kind_name(request.kind_case())};
  }
  if (request.has_chunk() || request.has_end()) return std::nullopt;
  return ServiceError{ErrorCode::kInvalidArgument, "message " + std::to_string(index) + " is " +
                                                       kind_name(request.kind_case()) +
                                                       "; expected a PointChunk or EndOfScan"};
}

StreamLimits::StreamLimits(const ops::ServerConfig& config, Clock::time_point now)
    : config_(config), last_message_(now) {}

void StreamLimits::message_arrived(std::uint64_t bytes, Clock::time_point now) {
  last_message_ = now;
  window_bytes_ += bytes;
}

void StreamLimits::receiving_started(Clock::time_point now) {
  window_start_ = now;
  window_bytes_ = 0;
  rate_check_at_ = now + 2 * seconds(config_.receive_rate_window_seconds);
}

void StreamLimits::write_started(Clock::time_point now) {
  write_pending_ = true;
  write_started_ = now;
}

Clock::time_point StreamLimits::next_check(StreamPhase phase) const {
  Clock::time_point next = Clock::time_point::max();
  if (receiving(phase)) next = std::min(next, last_message_ + seconds(config_.stream_idle_seconds));
  if (phase == StreamPhase::kReceiving && config_.min_receive_bytes_per_second > 0)
    next = std::min(next, rate_check_at_);
  if (phase == StreamPhase::kSending && write_pending_)
    next = std::min(next, write_started_ + seconds(config_.send_timeout_seconds));
  return next;
}

std::optional<ServiceError> StreamLimits::check(StreamPhase phase, Clock::time_point now) {
  if (receiving(phase) && now - last_message_ >= seconds(config_.stream_idle_seconds))
    return ServiceError{ErrorCode::kDeadlineExceeded,
                        std::string("no message came for ") + number(config_.stream_idle_seconds) +
                            " s while " + doing(phase) + " (--stream-idle-seconds)"};
  if (phase == StreamPhase::kReceiving && config_.min_receive_bytes_per_second > 0 &&
      now >= rate_check_at_) {
    const double elapsed = seconds_between(window_start_, now);
    const double rate = double(window_bytes_) / std::max(elapsed, 1e-9);
    if (rate < config_.min_receive_bytes_per_second)
      return ServiceError{ErrorCode::kResourceExhausted,
                          "the scan arrived at " + number(rate) + " bytes/s over the last " +
                              number(elapsed) + " s, under the server's minimum of " +
                              number(config_.min_receive_bytes_per_second) +
                              " bytes/s (--min-receive-bytes-per-second)"};
    window_start_ = now;
    window_bytes_ = 0;
    rate_check_at_ = now + seconds(config_.receive_rate_window_seconds);
  }
  if (phase == StreamPhase::kSending && write_pending_ &&
      now - write_started_ >= seconds(config_.send_timeout_seconds))
    return ServiceError{ErrorCode::kDeadlineExceeded, "the client took no answer message for " +
                                                          number(config_.send_timeout_seconds) +
                                                          " s (--send-timeout-seconds)"};
  return std::nullopt;
}

}  // namespace primlabel::service
