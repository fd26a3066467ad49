#pragma once
// What both labeling reactors need at the RPC edge: who may start, the deadline a call runs
// under, why a cancelled call ended, and the exception barrier's error.

#include <grpcpp/server_context.h>

#include <chrono>
#include <exception>
#include <optional>
#include <string>

#include "primlabel/rpc/auth.hpp"
#include "primlabel/service/service_environment.hpp"
#include "primlabel/service/service_error.hpp"

namespace primlabel::rpc {

// A draining server, or a caller without a valid token, is turned away before anything is read.
std::optional<service::ServiceError> may_start(const service::ServiceEnvironment& env,
                                               const TokenAuth& auth,
                                               const grpc::ServerContextBase& context);

// The earlier of the client's deadline and --max-request-seconds from now.
struct CallDeadline {
  std::chrono::steady_clock::time_point at;
  bool from_client = false;
  double server_limit_seconds = 0;

  static CallDeadline of(const grpc::ServerContextBase& context, const ops::ServerConfig& config);
  // DEADLINE_EXCEEDED naming which deadline passed and while doing what.
  service::ServiceError passed(const char* while_doing) const;
};

// Why a call the transport cancelled ended: the server shutting down (UNAVAILABLE), the
// client's deadline (DEADLINE_EXCEEDED) or the client (CANCELLED).
service::ServiceError cancel_reason(const service::ServiceEnvironment& env,
                                    const grpc::ServerContextBase& context,
                                    const char* while_doing);

// INTERNAL for an exception that reached the edge (the last line of defence).
service::ServiceError internal_error(const char* while_doing, std::exception_ptr error);

}  // namespace primlabel::rpc
