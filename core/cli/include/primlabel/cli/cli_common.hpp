#pragma once
// Small pieces every primlabel command-line tool shares: progress on stderr, parsing of vector
// arguments, and the exit codes of every binary (exit_codes.hpp).

#include <chrono>
#include <cstddef>
#include <string>
#include <vector>

#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/progress.hpp"

namespace primlabel::cli {

using ::primlabel::kExitFailure;
using ::primlabel::kExitOk;
using ::primlabel::kExitUsage;

// Parses "X,Y,Z" into a vector; throws std::invalid_argument with a readable reason.
Vec3f parse_vec3(const std::string& text);

// Prints "<stage>: 42% (1234/5678 points)" to stderr once a stage has run for a second:
// redrawn in place on a terminal, a line per 10% otherwise. Silent when quiet.
class ProgressPrinter {
 public:
  explicit ProgressPrinter(bool quiet);
  ProgressFn stage(const std::string& name);
  void done();  // ends the current stage's line

 private:
  void report(std::size_t done, std::size_t total);
  bool quiet_;
  bool tty_;
  std::string name_;
  std::chrono::steady_clock::time_point stage_start_;
  std::chrono::steady_clock::time_point last_print_;
  int last_decile_ = -1;
  bool printed_ = false;
};

}  // namespace primlabel::cli
