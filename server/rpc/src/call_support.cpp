#include "call_support.hpp"

#include <cmath>

#include "primlabel/service/job_plan.hpp"

namespace primlabel::rpc {

std::optional<service::ServiceError> may_start(const service::ServiceEnvironment& env,
                                               const TokenAuth& auth,
                                               const grpc::ServerContextBase& context) {
  if (env.draining->load()) return service::shutting_down();
  return auth.check(context, false);
}

CallDeadline CallDeadline::of(const grpc::ServerContextBase& context,
                              const ops::ServerConfig& config) {
  using namespace std::chrono;
  CallDeadline deadline;
  deadline.server_limit_seconds = config.max_request_seconds;
  const auto now = steady_clock::now();
  const auto limit = duration_cast<steady_clock::duration>(
      duration<double>(std::min(config.max_request_seconds, 1e7)));
  deadline.at = now + limit;
  const system_clock::time_point client = context.deadline();
  // An unset deadline is time_point::max(); keep the arithmetic away from it.
  const auto remaining = client - system_clock::now();
  if (client != system_clock::time_point::max() && remaining < limit) {
    deadline.at = now + duration_cast<steady_clock::duration>(remaining);
    deadline.from_client = true;
  }
  return deadline;
}

service::ServiceError CallDeadline::passed(const char* while_doing) const {
  if (from_client)
    return {service::ErrorCode::kDeadlineExceeded,
            std::string("the client's deadline passed while ") + while_doing};
  char limit[32];
  std::snprintf(limit, sizeof limit, "%g", server_limit_seconds);
  return {service::ErrorCode::kDeadlineExceeded,
          std::string("the request took longer than the server's ") + limit +
              " s limit (--max-request-seconds) while " + while_doing +
              "; set a deadline to allow more"};
}

service::ServiceError cancel_reason(const service::ServiceEnvironment& env,
                                    const grpc::ServerContextBase& context,
                                    const char* while_doing) {
  if (env.draining->load())
    return {service::ErrorCode::kUnavailable,
            std::string("the server shut down while ") + while_doing + "; retry elsewhere"};
  // The client's own timer fires first: the server's copy of the deadline was computed when the
  // call arrived, after the client's connection set-up and send had already used some of it.
  constexpr auto kClockLag = std::chrono::milliseconds(250);
  if (std::chrono::system_clock::now() + kClockLag >= context.deadline())
    return {service::ErrorCode::kDeadlineExceeded,
            std::string("the client's deadline passed while ") + while_doing};
  return {service::ErrorCode::kCancelled, std::string("the client cancelled while ") + while_doing};
}

service::ServiceError internal_error(const char* while_doing, std::exception_ptr error) {
  std::string what = "an unknown exception";
  try {
    if (error) std::rethrow_exception(error);
  } catch (const std::exception& e) {
    what = e.what();
  } catch (...) {
  }
  return {service::ErrorCode::kInternal,
          std::string("internal error while ") + while_doing + ": " + what};
}

}  // namespace primlabel::rpc
