#pragma once
// Writing the Prometheus text exposition format 0.0.4.

#include <string>
#include <string_view>
#include <vector>

#include "primlabel/metrics/family_snapshot.hpp"

namespace primlabel::metrics {

// The Content-Type of a /metrics response in this format.
inline constexpr std::string_view kTextContentType = "text/plain; version=0.0.4; charset=utf-8";

// HELP text: backslash and newline escaped.
std::string escape_help(std::string_view help);
// Label value: backslash, double quote and newline escaped.
std::string escape_label_value(std::string_view value);
// Shortest text that parses back to the same double; "+Inf", "-Inf", "NaN" as Prometheus writes.
std::string format_value(double value);

// Appends one family (HELP, TYPE, then its samples) to `out`. Families without metrics are
// skipped entirely.
void serialize_family(const FamilySnapshot& family, std::string& out);
std::string serialize(const std::vector<FamilySnapshot>& families);

}  // namespace primlabel::metrics
