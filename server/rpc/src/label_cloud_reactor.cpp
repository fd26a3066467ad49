// The unary LabelCloud RPC on the callback API (see label_reactors.hpp): the request is whole
// when the reactor starts, so it is checked, its answer's size weighed against the message
// limit and its job queued at once; the worker's end of the job answers the call.

#include <memory>
#include <mutex>

#include "call_support.hpp"
#include "label_reactors.hpp"
#include "message_codec.hpp"
#include "primlabel/rpc/grpc_status.hpp"
#include "primlabel/service/label_response.hpp"
#include "primlabel/service/labeling_session.hpp"
#include "primlabel/service/request_record.hpp"

namespace primlabel::rpc {

namespace {

using Clock = std::chrono::steady_clock;

// Room for the summary and the framing around the per-point arrays.
constexpr std::uint64_t kAnswerOverheadBytes = 4096;

class LabelCloudReactor final : public grpc::ServerUnaryReactor,
                                public std::enable_shared_from_this<LabelCloudReactor> {
 public:
  LabelCloudReactor(const service::ServiceEnvironment& env, const TokenAuth& auth,
                    grpc::CallbackServerContext* context, grpc::ByteBuffer* response)
      : env_(env),
        auth_(auth),
        context_(context),
        response_(response),
        record_("LabelCloud", *env.metrics),
        session_(env, record_),
        deadline_(CallDeadline::of(*context, *env.config)) {}

  void begin(const grpc::ByteBuffer* request) {
    std::lock_guard lock(mutex_);
    self_ = shared_from_this();
    try {
      start(*request);
    } catch (...) {
      fail(internal_error("reading the request", std::current_exception()));
    }
  }

  void OnCancel() override {
    std::lock_guard lock(mutex_);
    fail(cancel_reason(env_, *context_, "labeling"));
  }

  void OnDone() override {
    std::shared_ptr<LabelCloudReactor> keep;
    {
      std::lock_guard lock(mutex_);
      keep = std::move(self_);
    }
  }

 private:
  void start(const grpc::ByteBuffer& bytes) {
    if (auto refused = may_start(env_, auth_, *context_)) return fail(*refused);
    v1::LabelCloudRequest request;
    grpc::ByteBuffer copy(bytes);  // the reader consumes its buffer
    if (!parse_message(copy, request))
      return fail(
          {service::ErrorCode::kInvalidArgument, "the request is not a valid LabelCloudRequest"});
    if (!request.has_header())
      return fail({service::ErrorCode::kInvalidArgument, "the request has no header"});
    if (auto refused = session_.start(request.header(), /*streamed=*/false)) return fail(*refused);
    if (auto refused = session_.add(request.points())) return fail(*refused);
    request.Clear();
    // Known before labeling: an answer over the limit is refused before any work.
    const std::uint64_t answer = session_.answer_bytes();
    const auto limit = std::uint64_t(env_.config->max_message_bytes);
    if (answer + kAnswerOverheadBytes > limit)
      return fail({service::ErrorCode::kResourceExhausted,
                   "the response would take " + std::to_string(answer) +
                       " bytes, over the server's message limit of " + std::to_string(limit) +
                       " (--max-message-bytes); use the streaming Label RPC"});
    std::shared_ptr<LabelCloudReactor> self = shared_from_this();
    if (auto refused = session_.run([self] { self->labeled(); })) return fail(*refused);
    job_running_ = true;
    timer_ = env_.timers->schedule(deadline_.at, [weak = weak_from_this()] {
      if (auto self = weak.lock()) self->deadline_passed();
    });
  }

  void deadline_passed() {
    std::lock_guard lock(mutex_);
    timer_ = 0;
    fail(deadline_.passed("labeling"));
  }

  // On the worker thread, once the job ended.
  void labeled() {
    std::lock_guard lock(mutex_);
    job_running_ = false;
    if (finished_) return session_.free_result();
    try {
      if (auto failed = session_.outcome()) return fail(*failed);
      const service::LabelResponder responder(session_.result(), 0, std::uint64_t(-1));
      v1::LabelCloudResponse response;
      responder.fill_range(0, session_.result().labels.size(), *response.mutable_result());
      record_.stages.send = 0;
      service::fill_summary(record_, session_.plan(), session_.result(),
                            *response.mutable_summary());
      session_.free_result();
      *response_ = serialize_message(response);
      record_.stages.send =
          std::chrono::duration<double>(Clock::now() - session_.job_ended()).count();
      finish(grpc::Status::OK);
    } catch (...) {
      fail(internal_error("answering", std::current_exception()));
    }
  }

  void fail(const service::ServiceError& error) {
    if (finished_) return;
    if (job_running_ && session_.stop()) job_running_ = false;
    if (!job_running_) session_.free_result();
    response_->Clear();
    finish(to_grpc_status(error));
  }

  void finish(const grpc::Status& status) {
    finished_ = true;
    if (timer_) env_.timers->cancel(std::exchange(timer_, 0));
    try {
      finish_request(record_, status);
    } catch (...) {  // logging must not keep the call from finishing
    }
    Finish(status);
  }

  const service::ServiceEnvironment& env_;
  const TokenAuth& auth_;
  grpc::CallbackServerContext* const context_;
  grpc::ByteBuffer* const response_;
  std::mutex mutex_;
  std::shared_ptr<LabelCloudReactor> self_;
  bool finished_ = false;
  bool job_running_ = false;
  service::RequestRecord record_;
  service::LabelingSession session_;
  const CallDeadline deadline_;
  service::TimerService::Id timer_ = 0;
};

}  // namespace

grpc::ServerUnaryReactor* start_label_cloud_reactor(const service::ServiceEnvironment& env,
                                                    const TokenAuth& auth,
                                                    grpc::CallbackServerContext* context,
                                                    const grpc::ByteBuffer* request,
                                                    grpc::ByteBuffer* response) {
  try {
    auto reactor = std::make_shared<LabelCloudReactor>(env, auth, context, response);
    reactor->begin(request);
    return reactor.get();
  } catch (...) {  // the reactor could not even be made (out of memory): say so
    grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
    reactor->Finish(to_grpc_status(internal_error("starting the call", std::current_exception())));
    return reactor;
  }
}

}  // namespace primlabel::rpc
