#pragma once
// What the transport-neutral service layer answers when a request cannot be served: a code
// (the canonical RPC codes, so every transport can map them one to one) and a message naming
// what and where. grpc::Status is made from it in one place, at the RPC edge.

#include <string>

namespace primlabel::service {

enum class ErrorCode {
  kCancelled,
  kInvalidArgument,
  kDeadlineExceeded,
  kNotFound,
  kAlreadyExists,
  kPermissionDenied,
  kResourceExhausted,
  kFailedPrecondition,
  kAborted,
  kOutOfRange,
  kUnimplemented,
  kInternal,
  kUnavailable,
  kDataLoss,
  kUnauthenticated,
};

struct ServiceError {
  ErrorCode code = ErrorCode::kInternal;
  std::string message;
};

}  // namespace primlabel::service
