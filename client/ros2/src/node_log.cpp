#include "primlabel/ros2/node_log.hpp"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>

namespace primlabel::ros2node {

namespace {

constexpr const char* kNames[] = {"DEBUG", "INFO", "WARN", "ERROR", "FATAL"};

std::atomic<int> log_level{static_cast<int>(Severity::kInfo)};

}  // namespace

std::optional<Severity> severity_named(const std::string& name) {
  std::string upper = name;
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  for (int k = 0; k < 5; ++k)
    if (upper == kNames[k]) return static_cast<Severity>(k);
  return std::nullopt;
}

void set_log_level(Severity severity) { log_level.store(static_cast<int>(severity)); }

void log(Severity severity, const std::string& node, const std::string& text) {
  if (severity != Severity::kFatal && static_cast<int>(severity) < log_level.load()) return;
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  const long long ns = std::chrono::duration_cast<std::chrono::nanoseconds>(now).count();
  // One fprintf per line, so lines from different threads do not interleave.
  std::fprintf(stderr, "[%s] [%lld.%09lld] [%s]: %s\n", kNames[static_cast<int>(severity)],
               ns / 1'000'000'000, ns % 1'000'000'000, node.c_str(), text.c_str());
  std::fflush(stderr);
}

}  // namespace primlabel::ros2node
