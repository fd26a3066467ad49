#pragma once
// The load generator's results as text for people, CSV for spreadsheets and JSON for scripts:
// one row per step (a sweep has several).

#include <cstdio>
#include <optional>
#include <vector>

#include "load_runner.hpp"
#include "server_counters.hpp"

namespace primlabel::client::loadgen {

struct ReportRow {
  StepResult step;
  std::optional<ServerCounts> server;  // the server's count over the step, when --metrics-url
};

enum class ReportFormat { kText, kCsv, kJson };

void write_report(std::FILE* out, const std::vector<ReportRow>& rows, ReportFormat format);

}  // namespace primlabel::client::loadgen
