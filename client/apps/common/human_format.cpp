#include "human_format.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

namespace primlabel::client::tools {

std::string describe_age_ms(std::int64_t age_ms) {
  const std::int64_t s = std::max<std::int64_t>(0, age_ms) / 1000;  // clocks apart: not "-3 s"
  if (s < 120) return std::to_string(s) + " s";
  if (s < 2 * 3600) return std::to_string(s / 60) + " min";
  if (s < 2 * 86400) return std::to_string(s / 3600) + " h";
  return std::to_string(s / 86400) + " days";
}

std::string describe_unix_ms(std::int64_t unix_ms, std::int64_t now_unix_ms) {
  if (unix_ms == 0) return "unknown";
  const std::time_t seconds = static_cast<std::time_t>(unix_ms / 1000);
  std::tm utc{};
  char date[64] = "";
  // A time gmtime cannot represent (a corrupt field) prints as its number.
  if (!gmtime_r(&seconds, &utc) || !std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S UTC", &utc))
    return std::to_string(unix_ms) + " ms since 1970";
  const std::string age =
      unix_ms > now_unix_ms ? "in the future" : describe_age_ms(now_unix_ms - unix_ms) + " ago";
  return std::string(date) + " (" + age + ")";
}

std::string score_or_na(double value, int decimals) {
  if (!std::isfinite(value)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

}  // namespace primlabel::client::tools
