#pragma once
// The exit codes of `primlabel`, which scripts rely on (listed in --help): the scheme every
// primlabel binary shares (primlabel/cli/exit_codes.hpp) plus two of its own, and the
// status each gRPC outcome exits with.

#include <grpcpp/support/status.h>

#include "primlabel/cli/exit_codes.hpp"

namespace primlabel::client::tools {

using ::primlabel::kExitOk;
using ::primlabel::kExitUsage;
inline constexpr int kExitFile = ::primlabel::kExitFailure;  // an input or output file failed
inline constexpr int kExitUnavailable = 3;  // server unreachable, not serving, or too slow
inline constexpr int kExitRejected = 4;     // the server answered the request with an error
static_assert(kExitUnavailable >= ::primlabel::kExitFirstToolSpecific);

inline constexpr const char* kExitCodesHelp =
    "Exit codes: 0 ok, 1 input/output file error, 2 usage error, 3 server unavailable "
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
