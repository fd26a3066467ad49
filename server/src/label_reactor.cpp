// The streaming Label RPC: one reactor per call (see label_reactors.hpp). All state is under
// the reactor's mutex; the reactions come from gRPC's threads, the worker (labeling done) and
// the timer thread. The reactor owns itself (self_) until OnDone; a running job and a pending
// timer hold it through shared / weak pointers, so neither ever touches a destroyed reactor.

#include <algorithm>
#include <memory>
#include <mutex>
#include <optional>

#include "call_support.hpp"
#include "grpc_status.hpp"
#include "label_reactors.hpp"
#include "label_response.hpp"
#include "label_service.hpp"
#include "logging.hpp"
#include "message_codec.hpp"
#include "request_record.hpp"

namespace primlabel::server {

namespace {

using Clock = std::chrono::steady_clock;
using RawReactor = grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>;

Clock::duration seconds(double value) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(value));
}

double seconds_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
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

ServiceError invalid(const std::string& message) { return {ErrorCode::kInvalidArgument, message}; }

class LabelReactor final : public RawReactor, public std::enable_shared_from_this<LabelReactor> {
 public:
  LabelReactor(const ServiceEnvironment& env, grpc::CallbackServerContext* context)
      : env_(env),
        context_(context),
        record_("Label", *env.metrics),
        session_(env, record_),
        deadline_(CallDeadline::of(*context, *env.config)),
        last_message_(Clock::now()) {}

  void begin() {
    std::lock_guard lock(mutex_);
    self_ = shared_from_this();
    guarded("starting", [&] {
      if (auto refused = may_start(env_, *context_)) return fail(*refused);
      StartRead(&read_buffer_);
      arm_timer();
    });
  }

  void OnReadDone(bool ok) override {
    std::lock_guard lock(mutex_);
    if (phase_ == Phase::kFinished) return;
    guarded("reading the scan", [&] { ok ? take_message() : end_of_input(); });
  }

  void OnWriteDone(bool ok) override {
    std::lock_guard lock(mutex_);
    write_pending_ = false;
    if (phase_ == Phase::kFinished) return;
    if (!ok) return fail(cancel_reason(env_, *context_, "receiving labels"));
    guarded("sending labels", [&] { summary_sent_ ? finish_ok() : write_next(); });
  }

  void OnCancel() override {
    std::lock_guard lock(mutex_);
    if (phase_ == Phase::kFinished) return;
    fail(cancel_reason(env_, *context_, doing()));
  }

  void OnDone() override {
    std::shared_ptr<LabelReactor> keep;
    {
      std::lock_guard lock(mutex_);
      keep = std::move(self_);  // a running job or a firing timer may still hold the reactor
    }
  }

 private:
  enum class Phase { kHeader, kReceiving, kLabeling, kSending, kFinished };

  const char* doing() const {
    switch (phase_) {
      case Phase::kHeader:
        return "waiting for the ScanHeader";
      case Phase::kReceiving:
        return "receiving points";
      case Phase::kLabeling:
        return "labeling";
      default:
        return "sending labels";
    }
  }

  // The exception barrier: whatever a step throws fails this call alone.
  template <typename Step>
  void guarded(const char* while_doing, Step&& step) {
    try {
      step();
    } catch (...) {
      fail(internal_error(while_doing, std::current_exception()));
    }
  }

  void take_message() {
    const Clock::time_point now = Clock::now();
    last_message_ = now;
    window_bytes_ += read_buffer_.Length();
    const std::uint64_t index = ++messages_;
    v1::LabelRequest request;
    const bool parsed = parse_message(read_buffer_, request);
    read_buffer_.Clear();
    if (!parsed)
      return fail(invalid("message " + std::to_string(index) + " is not a valid LabelRequest"));
    if (phase_ == Phase::kHeader) {
      if (!request.has_header())
        return fail(invalid(std::string("message 1 must be a ScanHeader, got ") +
                            kind_name(request.kind_case())));
      if (auto refused = session_.start(request.header(), /*streamed=*/true)) return fail(*refused);
      phase_ = Phase::kReceiving;
      // The first rate window begins after a grace period of one window.
      window_start_ = now;
      window_bytes_ = 0;
      rate_check_at_ = now + 2 * seconds(env_.config->receive_rate_window_seconds);
      StartRead(&read_buffer_);
      return arm_timer();
    }
    if (request.has_end()) return scan_complete();
    if (!request.has_chunk())
      return fail(invalid("message " + std::to_string(index) + " is " +
                          kind_name(request.kind_case()) + "; expected a PointChunk or EndOfScan"));
    if (auto refused = session_.add(request.chunk())) return fail(*refused);
    StartRead(&read_buffer_);
  }

  // The client half-closed (which ends the scan) or went away.
  void end_of_input() {
    if (context_->IsCancelled()) return fail(cancel_reason(env_, *context_, doing()));
    if (phase_ == Phase::kHeader) return fail(invalid("the stream ended before a ScanHeader"));
    scan_complete();
  }

  void scan_complete() {
    phase_ = Phase::kLabeling;
    std::shared_ptr<LabelReactor> self = shared_from_this();
    if (auto refused = session_.run([self] { self->labeled(); })) return fail(*refused);
    job_running_ = true;
    arm_timer();
  }

  // On the worker thread, once the job ended.
  void labeled() {
    std::lock_guard lock(mutex_);
    job_running_ = false;
    if (phase_ == Phase::kFinished) {
      session_.free_result();
      log_info("labeling_stopped")
          .kv("request_id", record_.id())
          .kv("stop_ms", 1e3 * seconds_between(stopped_at_, Clock::now()));
      return;
    }
    guarded("answering", [&] {
      if (auto failed = session_.outcome()) return fail(*failed);
      phase_ = Phase::kSending;
      responder_.emplace(session_.result(), session_.header().options().response_chunk_points(),
                         env_.config->response_chunk_bytes);
      write_next();
    });
  }

  void write_next() {
    v1::LabelResponse response;
    if (next_chunk_ < responder_->chunk_count()) {
      responder_->fill_chunk(next_chunk_++, *response.mutable_chunk());
    } else {
      // From the job's end: the hand-over to this thread, packing and writing the chunks.
      record_.stages.send = seconds_between(session_.job_ended(), Clock::now());
      fill_summary(record_, session_.plan(), session_.result(), *response.mutable_summary());
      summary_sent_ = true;
    }
    write_buffer_ = serialize_message(response);
    write_pending_ = true;
    write_started_ = Clock::now();
    StartWrite(&write_buffer_);
    arm_timer();
  }

  void finish_ok() {
    phase_ = Phase::kFinished;
    cancel_timer();
    release_memory();
    finish_request(record_, grpc::Status::OK);
    Finish(grpc::Status::OK);
  }

  // Ends the call with `error` at once: the job is told to stop, the memory goes, the slots go
  // (the compute slot when the worker has stopped, within a block of points).
  void fail(const ServiceError& error) {
    if (phase_ == Phase::kFinished) return;
    const Phase was = phase_;
    phase_ = Phase::kFinished;
    stopped_at_ = Clock::now();
    cancel_timer();
    if (was == Phase::kLabeling && session_.stop()) job_running_ = false;
    release_memory();
    const grpc::Status status = to_grpc_status(error);
    try {
      finish_request(record_, status);
    } catch (...) {  // logging must not keep the call from finishing
    }
    // A client that does not read would hold a pending write, and with it the call, forever.
    if (write_pending_) context_->TryCancel();
    Finish(status);
  }

  void release_memory() {
    responder_.reset();
    write_buffer_.Clear();
    if (!job_running_) session_.free_result();  // else the worker writes it; labeled() frees it
  }

  // The next moment a limit could be reached; one timer per call, moved only when it must come
  // earlier (a later limit is re-armed when the timer fires).
  void arm_timer() {
    Clock::time_point next = deadline_.at;
    if (phase_ == Phase::kHeader || phase_ == Phase::kReceiving)
      next = std::min(next, last_message_ + seconds(env_.config->stream_idle_seconds));
    if (phase_ == Phase::kReceiving && env_.config->min_receive_bytes_per_second > 0)
      next = std::min(next, rate_check_at_);
    if (phase_ == Phase::kSending && write_pending_)
      next = std::min(next, write_started_ + seconds(env_.config->send_timeout_seconds));
    if (timer_ && timer_at_ <= next) return;
    cancel_timer();
    timer_at_ = next;
    timer_ = env_.timers->schedule(next, [weak = weak_from_this()] {
      if (auto self = weak.lock()) self->timer_fired();
    });
  }

  void cancel_timer() {
    if (timer_) env_.timers->cancel(std::exchange(timer_, 0));
  }

  void timer_fired() {
    std::lock_guard lock(mutex_);
    timer_ = 0;
    if (phase_ == Phase::kFinished) return;
    guarded("checking the stream's limits", [&] {
      const Clock::time_point now = Clock::now();
      const ServerConfig& config = *env_.config;
      if (now >= deadline_.at) return fail(deadline_.passed(doing()));
      if ((phase_ == Phase::kHeader || phase_ == Phase::kReceiving) &&
          now - last_message_ >= seconds(config.stream_idle_seconds))
        return fail({ErrorCode::kDeadlineExceeded,
                     std::string("no message came for ") + number(config.stream_idle_seconds) +
                         " s while " + doing() + " (--stream-idle-seconds)"});
      if (phase_ == Phase::kReceiving && config.min_receive_bytes_per_second > 0 &&
          now >= rate_check_at_) {
        const double elapsed = seconds_between(window_start_, now);
        const double rate = double(window_bytes_) / std::max(elapsed, 1e-9);
        if (rate < config.min_receive_bytes_per_second)
          return fail({ErrorCode::kResourceExhausted,
                       "the scan arrived at " + number(rate) + " bytes/s over the last " +
                           number(elapsed) + " s, under the server's minimum of " +
                           number(config.min_receive_bytes_per_second) +
                           " bytes/s (--min-receive-bytes-per-second)"});
        window_start_ = now;
        window_bytes_ = 0;
        rate_check_at_ = now + seconds(config.receive_rate_window_seconds);
      }
      if (phase_ == Phase::kSending && write_pending_ &&
          now - write_started_ >= seconds(config.send_timeout_seconds))
        return fail({ErrorCode::kDeadlineExceeded, "the client took no answer message for " +
                                                       number(config.send_timeout_seconds) +
                                                       " s (--send-timeout-seconds)"});
      arm_timer();
    });
  }

  static std::string number(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", value);
    return text;
  }

  const ServiceEnvironment& env_;
  grpc::CallbackServerContext* const context_;
  std::mutex mutex_;
  std::shared_ptr<LabelReactor> self_;
  Phase phase_ = Phase::kHeader;
  RequestRecord record_;
  LabelSession session_;
  const CallDeadline deadline_;

  grpc::ByteBuffer read_buffer_;
  std::uint64_t messages_ = 0;
  Clock::time_point last_message_;
  Clock::time_point window_start_, rate_check_at_;
  std::uint64_t window_bytes_ = 0;

  bool job_running_ = false;
  std::optional<LabelResponder> responder_;
  std::uint64_t next_chunk_ = 0;
  bool summary_sent_ = false;
  grpc::ByteBuffer write_buffer_;
  bool write_pending_ = false;
  Clock::time_point write_started_, stopped_at_;

  TimerService::Id timer_ = 0;
  Clock::time_point timer_at_;
};

// For a call whose reactor could not even be made (out of memory): it only says so.
class RefusedReactor final : public RawReactor {
 public:
  explicit RefusedReactor(const grpc::Status& status) { Finish(status); }
  void OnDone() override { delete this; }
};

}  // namespace

RawReactor* start_label_reactor(const ServiceEnvironment& env,
                                grpc::CallbackServerContext* context) {
  try {
    auto reactor = std::make_shared<LabelReactor>(env, context);
    reactor->begin();
    return reactor.get();
  } catch (...) {
    return new RefusedReactor(
        to_grpc_status(internal_error("starting the call", std::current_exception())));
  }
}

}  // namespace primlabel::server
