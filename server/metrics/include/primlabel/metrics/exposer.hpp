#pragma once
// Serves GET /metrics over HTTP/1.1 from registered registries, on a thread of its own.

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "primlabel/metrics/registry.hpp"

namespace primlabel::metrics {

// One poll() loop serves all connections (concurrent scrapers, keep-alive, pipelining,
// Connection: close), so a slow or idle client never blocks another. GET and HEAD /metrics
// (query string ignored) answer 200 with every live registry's text; any other path 404, other
// methods 405, malformed requests 400. Idle connections close after 60 s, at most 64 are open.
class Exposer {
 public:
  // "HOST:PORT", "[IPV6]:PORT" or ":PORT" (all interfaces); port 0 picks a free one. Throws
  // std::invalid_argument on a malformed address, std::runtime_error when it cannot listen.
  explicit Exposer(const std::string& bind_address);
  ~Exposer();  // stops the thread and closes every connection
  Exposer(const Exposer&) = delete;
  Exposer& operator=(const Exposer&) = delete;

  // Registries are held weakly: one that has been destroyed is skipped (and forgotten).
  void RegisterCollectable(const std::weak_ptr<Registry>& registry);
  void RemoveCollectable(const std::weak_ptr<Registry>& registry);

  std::uint16_t port() const { return port_; }

 private:
  void serve();
  std::string scrape();

  int listen_fd_ = -1;
  int wake_read_fd_ = -1;  // the destructor writes to wake_write_fd_ to stop the loop
  int wake_write_fd_ = -1;
  std::uint16_t port_ = 0;
  std::mutex collectables_mutex_;
  std::vector<std::weak_ptr<Registry>> collectables_;
  std::thread thread_;
};

}  // namespace primlabel::metrics
