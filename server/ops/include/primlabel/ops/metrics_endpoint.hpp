#pragma once
// The /metrics HTTP endpoint: prometheus-cpp's Exposer (civetweb) serving collectables.

#include <netinet/in.h>
#include <prometheus/collectable.h>
#include <prometheus/exposer.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace primlabel::ops {

class MetricsEndpoint {
 public:
  // Listens on "HOST:PORT" (HOST an IPv4 address or a name; port 0 picks a free one) or ":PORT"
  // (every IPv4 interface). Throws std::runtime_error naming the address and the reason when it
  // is malformed (std::invalid_argument from civetweb_listening_port) or cannot be bound.
  MetricsEndpoint(const std::string& address,
                  const std::vector<std::weak_ptr<prometheus::Collectable>>& collectables);
  // Stops within milliseconds (civetweb alone takes up to 2 s, see the .cpp).
  ~MetricsEndpoint();
  MetricsEndpoint(const MetricsEndpoint&) = delete;
  MetricsEndpoint& operator=(const MetricsEndpoint&) = delete;

  int port() const { return port_; }

 private:
  std::unique_ptr<prometheus::Exposer> exposer_;
  int port_ = 0;
  std::optional<sockaddr_in> listening_;  // where to connect to wake civetweb's accept loop
};

// civetweb's `listening_ports` value for a --metrics-listen address. civetweb reads that option
// as a list with suffixes ("80,443s", "8080r"), so anything but one plain host and port is
// refused here, with a reason. This build's civetweb has no IPv6, so "[...]" is refused too.
std::string civetweb_listening_port(const std::string& address);

}  // namespace primlabel::ops
