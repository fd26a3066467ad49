#pragma once
// Reading the Prometheus text exposition format (tests, and the load generator reading a
// server's counters). prometheus-cpp writes this format but has no reader.

#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace primlabel::scrape {

// Label name -> value. A std::map, so a label set has one canonical (sorted) order.
using Labels = std::map<std::string, std::string>;

struct Sample {
  std::string name;  // as written, e.g. "x_bucket" for a histogram bucket
  Labels labels;
  double value;
};

// Every sample line, in order. Comments (# HELP, # TYPE, others) and blank lines are checked
// where they have a form (TYPE names a known type) and otherwise skipped; timestamps are
// accepted and dropped. Throws std::invalid_argument("line N: ...") on malformed input.
std::vector<Sample> parse_exposition(std::string_view text);

// Sum of the values of samples named `name` whose labels include all of `match`
// (e.g. all statuses of one method). 0 when none match.
double sum_samples(const std::vector<Sample>& samples, std::string_view name,
                   const Labels& match = {});

}  // namespace primlabel::scrape
