#pragma once
// The server's own count of requests, read from its Prometheus endpoint
// (primlabel_requests_total{method,model,status}), to set beside the load generator's counts.

#include <map>
#include <string>

namespace primlabel::client::loadgen {

struct ServerCounts {
  double total = 0;
  std::map<std::string, double> by_status;

  ServerCounts operator-(const ServerCounts& before) const;
};

// The URL to scrape for a --metrics-url value: a URL ("http://host:port/metrics") as given,
// "HOST:PORT" as http://HOST:PORT/metrics, "HOST:PORT/PATH" as http://HOST:PORT/PATH; a URL
// without a path (or with "/" alone) gets /metrics. Throws std::invalid_argument on an empty
// value, no host, a scheme other than http(s), or blanks and control characters.
std::string metrics_url_from(const std::string& flag);

// Sums primlabel_requests_total over models for `method` ("Label" or "LabelCloud"; a method label
// written as the full "/primlabel.v1.Labeler/Label" matches too), from metrics_url_from(`where`).
// Throws std::runtime_error when the endpoint cannot be read or parsed.
ServerCounts read_server_counts(const std::string& where, const std::string& method,
                                int timeout_ms = 5000);

// Same, from exposition text already fetched.
ServerCounts parse_server_counts(const std::string& exposition, const std::string& method);

}  // namespace primlabel::client::loadgen
