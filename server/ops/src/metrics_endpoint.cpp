#include "primlabel/ops/metrics_endpoint.hpp"

#include <netdb.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace primlabel::ops {
namespace {

bool is_host_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
         c == '-' || c == '_';
}

// civetweb's worker threads: a few concurrent scrapers, and slow or idle connections are cut
// after the request timeout so they cannot hold every thread.
constexpr const char* kThreads = "4";
constexpr const char* kRequestTimeoutMs = "10000";

// An IPv4 address to reach the endpoint at: its host, or loopback when it listens on every
// interface. nullopt when the name does not resolve (the endpoint then just stops slowly).
std::optional<sockaddr_in> reachable_address(const std::string& host, int port) {
  const std::string target = host.empty() || host == "0.0.0.0" ? "127.0.0.1" : host;
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (getaddrinfo(target.c_str(), nullptr, &hints, &found) != 0 || !found) return std::nullopt;
  sockaddr_in address{};
  std::memcpy(&address, found->ai_addr, std::min<std::size_t>(found->ai_addrlen, sizeof address));
  freeaddrinfo(found);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  return address;
}

// Opens and closes one connection, with a 100 ms bound on connecting.
void knock(const sockaddr_in& address) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return;
  const timeval timeout{0, 100'000};
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
  connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address);
  close(fd);
}

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
  listening_ = reachable_address(address.substr(0, address.rfind(':')), port_);
}

MetricsEndpoint::~MetricsEndpoint() {
  // civetweb's accept loop polls its sockets with a 2 s timeout and looks at its stop flag only
  // in between, so stopping would take up to 2 s (every server shutdown, every test server).
  // Connections wake the poll; knock until the exposer is gone (bounded: 5 s at most).
  std::atomic<bool> stopped{false};
  std::jthread waker;
  if (listening_)
    waker = std::jthread([&stopped, address = *listening_] {
      for (int i = 0; i < 250 && !stopped.load(); ++i) {
        knock(address);
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    });
  exposer_.reset();
  stopped.store(true);
}

}  // namespace primlabel::ops
