#pragma once
// Structured one-line logs on stderr: `ts=... level=info event=label request_id=... points=...`.
// Values with spaces, quotes or '=' are quoted, so every line splits into key=value pairs.

#include <cstdint>
#include <sstream>
#include <string>
#include <string_view>

namespace primlabel::ops {

enum class LogLevel { kDebug, kInfo, kWarn, kError };

// Lines below this level are dropped; "debug", "info", "warn", "error". Throws
// std::invalid_argument for other names.
void set_log_level(LogLevel level);
LogLevel parse_log_level(std::string_view name);

// Collects key=value pairs and writes the line (atomically with respect to other lines) when it
// goes out of scope.
class LogLine {
 public:
  LogLine(LogLevel level, std::string_view event);
  ~LogLine();
  LogLine(const LogLine&) = delete;
  LogLine& operator=(const LogLine&) = delete;

  LogLine& kv(std::string_view key, std::string_view value);
  LogLine& kv(std::string_view key, const std::string& value) {
    return kv(key, std::string_view(value));
  }
  LogLine& kv(std::string_view key, const char* value) { return kv(key, std::string_view(value)); }
  LogLine& kv(std::string_view key, double value);
  LogLine& kv(std::string_view key, std::uint64_t value);
  LogLine& kv(std::string_view key, std::int64_t value);
  LogLine& kv(std::string_view key, int value) { return kv(key, std::int64_t(value)); }
  LogLine& kv(std::string_view key, unsigned value) { return kv(key, std::uint64_t(value)); }
  LogLine& kv(std::string_view key, bool value) { return kv(key, value ? "true" : "false"); }

 private:
  bool enabled_;
  std::string text_;
};

inline LogLine log_info(std::string_view event) { return LogLine(LogLevel::kInfo, event); }
inline LogLine log_warn(std::string_view event) { return LogLine(LogLevel::kWarn, event); }
inline LogLine log_error(std::string_view event) { return LogLine(LogLevel::kError, event); }
inline LogLine log_debug(std::string_view event) { return LogLine(LogLevel::kDebug, event); }

}  // namespace primlabel::ops
