#pragma once
// The exit codes of `primlabel`, which scripts rely on (listed in --help).

#include <grpcpp/support/status.h>

namespace primlabel::client::tools {

inline constexpr int kExitOk = 0;
inline constexpr int kExitUsage = 1;
inline constexpr int kExitFile = 2;         // an input (or output) file could not be read/written
inline constexpr int kExitUnavailable = 3;  // server unreachable, not serving, or too slow
inline constexpr int kExitRejected = 4;     // the server answered the request with an error

inline constexpr const char* kExitCodesHelp =
    "Exit codes: 0 ok, 1 usage error, 2 input/output file error, 3 server unavailable "
    "(unreachable, NOT_SERVING or deadline exceeded), 4 server rejected the request (its "
    "status is shown).";

inline int exit_code_for(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return kExitOk;
    case grpc::StatusCode::UNAVAILABLE:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return kExitUnavailable;
    default:
      return kExitRejected;
  }
}

}  // namespace primlabel::client::tools
