#include "server_counters.hpp"

#include <stdexcept>

#include "primlabel/metrics/exposition_parser.hpp"
#include "primlabel/metrics/http_client.hpp"

namespace primlabel::client::loadgen {

namespace {

bool method_matches(const std::string& label, const std::string& method) {
  return label == method || (label.size() > method.size() + 1 && label.ends_with("/" + method));
}

}  // namespace

ServerCounts ServerCounts::operator-(const ServerCounts& before) const {
  ServerCounts delta = *this;
  delta.total -= before.total;
  for (const auto& [status, n] : before.by_status) delta.by_status[status] -= n;
  std::erase_if(delta.by_status, [](const auto& entry) { return entry.second == 0; });
  return delta;
}

ServerCounts parse_server_counts(const std::string& exposition, const std::string& method) {
  ServerCounts counts;
  std::vector<metrics::Sample> samples;
  try {
    samples = metrics::parse_exposition(exposition);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("metrics: ") + e.what());
  }
  for (const auto& s : samples) {
    if (s.name != "primlabel_requests_total") continue;
    const auto m = s.labels.find("method");
    if (m == s.labels.end() || !method_matches(m->second, method)) continue;
    const auto status = s.labels.find("status");
    counts.by_status[status == s.labels.end() ? "" : status->second] += s.value;
    counts.total += s.value;
  }
  return counts;
}

ServerCounts read_server_counts(const std::string& host_port, const std::string& method,
                                int timeout_ms) {
  return parse_server_counts(metrics::http_get(host_port, "/metrics", timeout_ms), method);
}

}  // namespace primlabel::client::loadgen
