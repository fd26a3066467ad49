#pragma once
// The one place where the service layer's errors become gRPC statuses (the RPC edge).

#include <grpcpp/support/status.h>

#include "primlabel/service/request_record.hpp"
#include "primlabel/service/service_error.hpp"

namespace primlabel::rpc {

grpc::Status to_grpc_status(const service::ServiceError& error);

// Finishes the request's record with `status`; returns it, for `return finish_request(...)`.
grpc::Status finish_request(service::RequestRecord& record, const grpc::Status& status);

}  // namespace primlabel::rpc
