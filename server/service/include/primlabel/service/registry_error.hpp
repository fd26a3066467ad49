#pragma once
// The service error for a registry failure.

#include "primlabel/service/model_registry.hpp"
#include "primlabel/service/service_error.hpp"

namespace primlabel::service {

inline ServiceError registry_error(const RegistryError& error) {
  switch (error.kind()) {
    case RegistryError::Kind::kNotFound:
      return {ErrorCode::kNotFound, error.what()};
    case RegistryError::Kind::kInvalidArgument:
      return {ErrorCode::kInvalidArgument, error.what()};
    case RegistryError::Kind::kLoadFailed:
      return {ErrorCode::kFailedPrecondition, error.what()};
  }
  return {ErrorCode::kInternal, error.what()};
}

}  // namespace primlabel::service
