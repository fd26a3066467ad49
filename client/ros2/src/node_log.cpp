#include "node_log.hpp"

#include <chrono>
#include <cstdio>

namespace primlabel::ros2node {

void log(Severity severity, const std::string& node, const std::string& text) {
  static const char* const names[] = {"INFO", "WARN", "ERROR", "FATAL"};
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  const long long ns = std::chrono::duration_cast<std::chrono::nanoseconds>(now).count();
  // One fprintf per line, so lines from different threads do not interleave.
  std::fprintf(stderr, "[%s] [%lld.%09lld] [%s]: %s\n", names[static_cast<int>(severity)],
               ns / 1'000'000'000, ns % 1'000'000'000, node.c_str(), text.c_str());
  std::fflush(stderr);
}

}  // namespace primlabel::ros2node
