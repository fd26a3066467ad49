#pragma once
// A tiny blocking HTTP/1.1 client, enough to scrape /metrics.

#include <map>
#include <string>

namespace primlabel::metrics {

struct HttpResponse {
  int status = 0;
  std::map<std::string, std::string> headers;  // names lower-cased
  std::string body;
};

// One request ("Connection: close") to "HOST:PORT" or "[IPV6]:PORT". The whole exchange must
// finish within timeout_ms; throws std::runtime_error on timeout, connection or protocol errors.
HttpResponse http_request(const std::string& host_port, const std::string& path, int timeout_ms,
                          const std::string& method = "GET");

// The body of a GET; throws std::runtime_error unless the status is 200.
std::string http_get(const std::string& host_port, const std::string& path, int timeout_ms);

}  // namespace primlabel::metrics
