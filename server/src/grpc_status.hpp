#pragma once
// The one place where the service layer's errors become gRPC statuses (the RPC edge).

#include <grpcpp/support/status.h>

#include "service_error.hpp"

namespace primlabel::server {

grpc::Status to_grpc_status(const ServiceError& error);

}  // namespace primlabel::server
