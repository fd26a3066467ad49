// The streaming Label RPC: one reactor per call (see label_reactors.hpp). All state is under
// the reactor's mutex; the reactions come from gRPC's threads, the worker (labeling done) and
// the timer thread. The reactor owns itself (self_) until OnDone; a running job and a pending
// timer hold it through shared / weak pointers, so neither ever touches a destroyed reactor.

#include <algorithm>
#include <memory>
#include <mutex>
#include <optional>

#include "call_support.hpp"
#include "label_reactors.hpp"
#include "message_codec.hpp"
#include "primlabel/ops/logging.hpp"
#include "primlabel/rpc/grpc_status.hpp"
#include "primlabel/service/label_response.hpp"
#include "primlabel/service/labeling_session.hpp"
#include "primlabel/service/request_record.hpp"
#include "primlabel/service/stream_limits.hpp"

namespace primlabel::rpc {

namespace {

using Clock = std::chrono::steady_clock;
using RawReactor = grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>;

double seconds_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

service::ServiceError invalid(const std::string& message) {
  return {service::ErrorCode::kInvalidArgument, message};
}

class LabelReactor final : public RawReactor, public std::enable_shared_from_this<LabelReactor> {
 public:
  LabelReactor(const service::ServiceEnvironment& env, const TokenAuth& auth,
               grpc::CallbackServerContext* context)
      : env_(env),
        auth_(auth),
        context_(context),
        record_("Label", *env.metrics),
        session_(env, record_),
        deadline_(CallDeadline::of(*context, *env.config)),
        limits_(*env.config, Clock::now()) {}

  void begin() {
    std::lock_guard lock(mutex_);
    self_ = shared_from_this();
    guarded("starting", [&] {
      if (auto refused = may_start(env_, auth_, *context_)) return fail(*refused);
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
    limits_.write_done();
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
  using Phase = service::StreamPhase;
  const char* doing() const { return service::doing(phase_); }

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
    limits_.message_arrived(read_buffer_.Length(), now);
    const std::uint64_t index = ++messages_;
    v1::LabelRequest request;
    const bool parsed = parse_message(read_buffer_, request);
    read_buffer_.Clear();
    if (!parsed)
      return fail(invalid("message " + std::to_string(index) + " is not a valid LabelRequest"));
    if (auto refused = service::out_of_order(phase_, request, index)) return fail(*refused);
    if (phase_ == Phase::kHeader) {
      if (auto refused = session_.start(request.header(), /*streamed=*/true)) return fail(*refused);
      phase_ = Phase::kReceiving;
      limits_.receiving_started(now);
      StartRead(&read_buffer_);
      return arm_timer();
    }
    if (request.has_end()) return scan_complete();
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
      ops::log_info("labeling_stopped")
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
      service::fill_summary(record_, session_.plan(), session_.result(),
                            *response.mutable_summary());
      summary_sent_ = true;
    }
    write_buffer_ = serialize_message(response);
    limits_.write_started(Clock::now());
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
  void fail(const service::ServiceError& error) {
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
    if (limits_.write_pending()) context_->TryCancel();
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
    const Clock::time_point next = std::min(deadline_.at, limits_.next_check(phase_));
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
      if (now >= deadline_.at) return fail(deadline_.passed(doing()));
      if (auto broken = limits_.check(phase_, now)) return fail(*broken);
      arm_timer();
    });
  }

  const service::ServiceEnvironment& env_;
  const TokenAuth& auth_;
  grpc::CallbackServerContext* const context_;
  std::mutex mutex_;
  std::shared_ptr<LabelReactor> self_;
  Phase phase_ = Phase::kHeader;
  service::RequestRecord record_;
  service::LabelingSession session_;
  const CallDeadline deadline_;

  service::StreamLimits limits_;

  grpc::ByteBuffer read_buffer_;
  std::uint64_t messages_ = 0;

  bool job_running_ = false;
  std::optional<service::LabelResponder> responder_;
  std::uint64_t next_chunk_ = 0;
  bool summary_sent_ = false;
  grpc::ByteBuffer write_buffer_;
  Clock::time_point stopped_at_;

  service::TimerService::Id timer_ = 0;
  Clock::time_point timer_at_;
};

// For a call whose reactor could not even be made (out of memory): it only says so.
class RefusedReactor final : public RawReactor {
 public:
  explicit RefusedReactor(const grpc::Status& status) { Finish(status); }
  void OnDone() override { delete this; }
};

}  // namespace

RawReactor* start_label_reactor(const service::ServiceEnvironment& env, const TokenAuth& auth,
                                grpc::CallbackServerContext* context) {
  try {
    auto reactor = std::make_shared<LabelReactor>(env, auth, context);
    reactor->begin();
    return reactor.get();
  } catch (...) {
    return new RefusedReactor(
        to_grpc_status(internal_error("starting the call", std::current_exception())));
  }
}

}  // namespace primlabel::rpc
