#include "primlabel/rpc/grpc_status.hpp"

#include "primlabel/wire/status_names.hpp"

namespace primlabel::rpc {

namespace {

grpc::StatusCode grpc_code(service::ErrorCode code) {
  switch (code) {
    case service::ErrorCode::kCancelled:
      return grpc::StatusCode::CANCELLED;
    case service::ErrorCode::kInvalidArgument:
      return grpc::StatusCode::INVALID_ARGUMENT;
    case service::ErrorCode::kDeadlineExceeded:
      return grpc::StatusCode::DEADLINE_EXCEEDED;
    case service::ErrorCode::kNotFound:
      return grpc::StatusCode::NOT_FOUND;
    case service::ErrorCode::kAlreadyExists:
      return grpc::StatusCode::ALREADY_EXISTS;
    case service::ErrorCode::kPermissionDenied:
      return grpc::StatusCode::PERMISSION_DENIED;
    case service::ErrorCode::kResourceExhausted:
      return grpc::StatusCode::RESOURCE_EXHAUSTED;
    case service::ErrorCode::kFailedPrecondition:
      return grpc::StatusCode::FAILED_PRECONDITION;
    case service::ErrorCode::kAborted:
      return grpc::StatusCode::ABORTED;
    case service::ErrorCode::kOutOfRange:
      return grpc::StatusCode::OUT_OF_RANGE;
    case service::ErrorCode::kUnimplemented:
      return grpc::StatusCode::UNIMPLEMENTED;
    case service::ErrorCode::kInternal:
      return grpc::StatusCode::INTERNAL;
    case service::ErrorCode::kUnavailable:
      return grpc::StatusCode::UNAVAILABLE;
    case service::ErrorCode::kDataLoss:
      return grpc::StatusCode::DATA_LOSS;
    case service::ErrorCode::kUnauthenticated:
      return grpc::StatusCode::UNAUTHENTICATED;
  }
  return grpc::StatusCode::INTERNAL;
}

}  // namespace

grpc::Status to_grpc_status(const service::ServiceError& error) {
  return {grpc_code(error.code), error.message};
}

grpc::Status finish_request(service::RequestRecord& record, const grpc::Status& status) {
  record.finish(::primlabel::wire::status_code_name(status.error_code()), status.error_message());
  return status;
}

}  // namespace primlabel::rpc
