#pragma once
// Figures as people read them in the CLI's output: times as UTC dates with their age, scores
// that may be undefined (a class with no validation points has no F1) as "n/a".

#include <cstdint>
#include <string>

namespace primlabel::client::tools {

// "2026-12-02 06:34:54 UTC (3 min ago)"; "unknown" for 0 (never set). `now_unix_ms` is the
// reference for the age; a time after it reads "(in the future)".
std::string describe_unix_ms(std::int64_t unix_ms, std::int64_t now_unix_ms);

// "45 s", "3 min", "5 h", "2 days": the age rounded down to its largest unit.
std::string describe_age_ms(std::int64_t age_ms);

// printf("%.*f") of a finite value, "n/a" for NaN and infinities.
std::string score_or_na(double value, int decimals = 3);

}  // namespace primlabel::client::tools
