#pragma once
// The canonical names of gRPC status codes ("DEADLINE_EXCEEDED"), the one table the server (logs,
// metric labels) and the clients (errors, load reports) share, so both spell a status alike.

#include <grpcpp/support/status.h>

#include <array>
#include <string>

namespace primlabel::wire {

// In the order of grpc::StatusCode (0 = OK ... 16 = UNAUTHENTICATED).
inline constexpr std::array<const char*, 17> kStatusCodeNames = {
    "OK",        "CANCELLED",      "UNKNOWN",           "INVALID_ARGUMENT",   "DEADLINE_EXCEEDED",
    "NOT_FOUND", "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION",
    "ABORTED",   "OUT_OF_RANGE",   "UNIMPLEMENTED",     "INTERNAL",           "UNAVAILABLE",
    "DATA_LOSS", "UNAUTHENTICATED"};

// A code outside the table (a newer gRPC, a corrupt value) is "STATUS_<n>", never a wrong name.
inline std::string status_code_name(grpc::StatusCode code) {
  const int i = static_cast<int>(code);
  return i >= 0 && i < static_cast<int>(kStatusCodeNames.size()) ? kStatusCodeNames[i]
                                                                 : "STATUS_" + std::to_string(i);
}

}  // namespace primlabel::wire
