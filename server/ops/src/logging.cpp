#include "primlabel/ops/logging.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <stdexcept>

namespace primlabel::ops {

namespace {

std::atomic<LogLevel> g_level{LogLevel::kInfo};
std::mutex g_write_mutex;

const char* level_name(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug:
      return "debug";
    case LogLevel::kInfo:
      return "info";
    case LogLevel::kWarn:
      return "warn";
    case LogLevel::kError:
      return "error";
  }
  return "info";
}

std::string timestamp() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", utc.tm_year + 1900,
                utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, int(ms));
  return buffer;
}

bool needs_quotes(std::string_view value) {
  if (value.empty()) return true;
  for (char c : value)
    if (c == ' ' || c == '"' || c == '=' || c == '\\' || static_cast<unsigned char>(c) < 0x20)
      return true;
  return false;
}

void append_value(std::string& out, std::string_view value) {
  if (!needs_quotes(value)) {
    out += value;
    return;
  }
  out += '"';
  for (char c : value) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += ' ';
    } else {
      out += c;
    }
  }
  out += '"';
}

}  // namespace

void set_log_level(LogLevel level) { g_level.store(level); }

LogLevel parse_log_level(std::string_view name) {
  if (name == "debug") return LogLevel::kDebug;
  if (name == "info") return LogLevel::kInfo;
  if (name == "warn") return LogLevel::kWarn;
  if (name == "error") return LogLevel::kError;
  throw std::invalid_argument("unknown log level '" + std::string(name) +
                              "' (debug, info, warn, error)");
}

LogLine::LogLine(LogLevel level, std::string_view event) : enabled_(level >= g_level.load()) {
  if (!enabled_) return;
  text_ = "ts=" + timestamp() + " level=" + level_name(level) + " event=";
  append_value(text_, event);
}

LogLine::~LogLine() {
  if (!enabled_) return;
  text_ += '\n';
  std::lock_guard lock(g_write_mutex);
  std::fwrite(text_.data(), 1, text_.size(), stderr);
  std::fflush(stderr);
}

LogLine& LogLine::kv(std::string_view key, std::string_view value) {
  if (!enabled_) return *this;
  text_ += ' ';
  text_ += key;
  text_ += '=';
  append_value(text_, value);
  return *this;
}

LogLine& LogLine::kv(std::string_view key, double value) {
  if (!enabled_) return *this;
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return kv(key, std::string_view(buffer));
}

LogLine& LogLine::kv(std::string_view key, std::uint64_t value) {
  return enabled_ ? kv(key, std::string_view(std::to_string(value))) : *this;
}

LogLine& LogLine::kv(std::string_view key, std::int64_t value) {
  return enabled_ ? kv(key, std::string_view(std::to_string(value))) : *this;
}

}  // namespace primlabel::ops
