#pragma once
// The gRPC status for a registry failure.

#include <grpcpp/support/status.h>

#include "model_registry.hpp"

namespace primlabel::server {

inline grpc::Status registry_status(const RegistryError& error) {
  switch (error.kind()) {
    case RegistryError::Kind::kNotFound:
      return {grpc::StatusCode::NOT_FOUND, error.what()};
    case RegistryError::Kind::kInvalidArgument:
      return {grpc::StatusCode::INVALID_ARGUMENT, error.what()};
    case RegistryError::Kind::kLoadFailed:
      return {grpc::StatusCode::FAILED_PRECONDITION, error.what()};
  }
  return {grpc::StatusCode::INTERNAL, error.what()};
}

}  // namespace primlabel::server
