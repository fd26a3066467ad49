#pragma once
// The exit codes of every primlabel binary (offline tools, server, clients, benchmarks), so a
// script can tell a failed run from a mistyped command the same way everywhere:
//   0 ok, 1 the run failed (unreadable input, unwritable output, could not start, ...),
//   2 bad usage (including every command-line parse error).
// Codes from 3 up are tool-specific and documented in that tool's --help and README section
// (e.g. the clients' 3 = server unavailable, 4 = request rejected).

namespace primlabel {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;
inline constexpr int kExitFirstToolSpecific = 3;

}  // namespace primlabel
