#include "metrics_endpoint.hpp"

#include <algorithm>
#include <charconv>
#include <stdexcept>

namespace primlabel::server {
namespace {

bool is_host_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
         c == '-' || c == '_';
}

// civetweb's worker threads: a few concurrent scrapers, and slow or idle connections are cut
// after the request timeout so they cannot hold every thread.
constexpr const char* kThreads = "4";
constexpr const char* kRequestTimeoutMs = "10000";

}  // namespace

std::string civetweb_listening_port(const std::string& address) {
  const auto colon = address.rfind(':');
  if (colon == std::string::npos) throw std::invalid_argument("expected HOST:PORT or :PORT");
  const std::string host = address.substr(0, colon);
  const std::string port = address.substr(colon + 1);
  if (host.starts_with('['))
    throw std::invalid_argument("IPv6 addresses are not supported (civetweb built without IPv6)");
  if (host.size() > 253) throw std::invalid_argument("the host is longer than a DNS name can be");
  if (!std::all_of(host.begin(), host.end(), is_host_char))
    throw std::invalid_argument("the host may hold only letters, digits, '.', '-' and '_'");
  unsigned value = 0;
  const auto [end, error] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (port.empty() || error != std::errc() || end != port.data() + port.size() || value > 65535)
    throw std::invalid_argument("the port must be a number from 0 to 65535");
  return host.empty() ? port : host + ":" + port;
}

MetricsEndpoint::MetricsEndpoint(
    const std::string& address,
    const std::vector<std::weak_ptr<prometheus::Collectable>>& collectables) {
  const auto fail = [&address](const std::string& why) {
    return std::runtime_error("cannot serve /metrics on '" + address + "': " + why);
  };
  std::string listening_port;
  try {
    listening_port = civetweb_listening_port(address);
  } catch (const std::invalid_argument& e) {
    throw fail(e.what());
  }
  try {
    exposer_ = std::make_unique<prometheus::Exposer>(
        std::vector<std::string>{"listening_ports", listening_port, "num_threads", kThreads,
                                 "request_timeout_ms", kRequestTimeoutMs});
  } catch (const std::exception& e) {
    // civetweb says only "null context ... Possible problem binding to port."
    throw fail(std::string("cannot bind (in use, or not an address of this host): ") + e.what());
  }
  for (const auto& collectable : collectables) exposer_->RegisterCollectable(collectable);
  const std::vector<int> ports = exposer_->GetListeningPorts();
  if (ports.empty()) throw fail("civetweb reports no listening port");
  port_ = ports.front();
}

}  // namespace primlabel::server
