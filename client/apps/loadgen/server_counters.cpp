#include "server_counters.hpp"

#include <algorithm>
#include <stdexcept>

#include "primlabel/scrape/exposition_parser.hpp"
#include "primlabel/scrape/http_fetch.hpp"

namespace primlabel::client::loadgen {

namespace {

bool is_blank_or_control(char c) { return static_cast<unsigned char>(c) <= ' ' || c == 0x7f; }

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
  std::vector<scrape::Sample> samples;
  try {
    samples = scrape::parse_exposition(exposition);
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

std::string metrics_url_from(const std::string& flag) {
  if (flag.empty()) throw std::invalid_argument("empty metrics URL");
  if (std::any_of(flag.begin(), flag.end(), is_blank_or_control))
    throw std::invalid_argument("blank or control character in the metrics URL");
  const auto scheme_end = flag.find("://");
  std::string url = scheme_end == std::string::npos ? "http://" + flag : flag;  // HOST:PORT[/PATH]
  if (scheme_end != std::string::npos) {
    const std::string scheme = flag.substr(0, scheme_end);
    if (scheme != "http" && scheme != "https")
      throw std::invalid_argument("metrics URL scheme '" + scheme + "' is not http or https");
  }
  const auto authority = url.find("://") + 3;
  if (authority == url.size() || url[authority] == '/')
    throw std::invalid_argument("no host in the metrics URL");
  // No path, or "/": the exposer's /metrics (its "/" answers 404).
  const auto path = url.find('/', authority);
  if (path == std::string::npos) return url + "/metrics";
  if (path + 1 == url.size()) return url + "metrics";
  return url;
}

ServerCounts read_server_counts(const std::string& where, const std::string& method,
                                int timeout_ms) {
  std::string url;
  try {
    url = metrics_url_from(where);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  return parse_server_counts(scrape::fetch_text(url, {.timeout_ms = timeout_ms}), method);
}

}  // namespace primlabel::client::loadgen
