#pragma once
// JSON output of every primlabel binary goes through nlohmann-json: escaping is its job, not ours.
// Two things it does not decide for us:
// - Strings we print come from file names and servers: invalid UTF-8 in them is replaced with
//   U+FFFD instead of throwing (nlohmann's default) in the middle of a report.
// - Reports print measured numbers at a stated precision; rounded() keeps exactly the digits the
//   printf format gave ("%.6f", "%.1f", "%.6g"), and null for NaN and infinities.
// Header-only: link nlohmann_json::nlohmann_json where it is included.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

namespace primlabel::json {

// Objects keep their keys in insertion order, so reports read the way they are written.
using Json = nlohmann::ordered_json;

// One line (indent < 0) or pretty-printed with `indent` spaces; never throws on bad UTF-8.
inline std::string dump(const Json& value, int indent = -1) {
  return value.dump(indent, ' ', false, Json::error_handler_t::replace);
}

// `value` as printf(format) shows it (e.g. "%.6f": 0.5 -> 0.5, 1/3 -> 0.333333), as a JSON number;
// null when it is not finite (JSON has no NaN).
inline Json rounded(double value, const char* format) {
  if (!std::isfinite(value)) return nullptr;
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return std::strtod(buffer, nullptr);
}

// `value` rounded to an integer (what "%.0f" showed: counters, points per second); null when it
// is not finite or does not fit.
inline Json whole(double value) {
  if (!std::isfinite(value) || std::fabs(value) >= 9.2e18) return nullptr;
  return static_cast<long long>(std::llround(value));
}

// A finite number or null.
inline Json number_or_null(double value) {
  if (!std::isfinite(value)) return nullptr;
  return value;
}

}  // namespace primlabel::json
