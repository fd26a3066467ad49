#pragma once
// Socket plumbing shared by the exposer and the HTTP client (internal to primlabel_metrics).

#include <chrono>
#include <string>
#include <utility>

namespace primlabel::metrics::detail {

// Owns a file descriptor; closes it on destruction.
class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) : fd_(fd) {}
  UniqueFd(UniqueFd&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  UniqueFd& operator=(UniqueFd&& other) noexcept;
  ~UniqueFd() { reset(); }
  int get() const { return fd_; }
  int release() { return std::exchange(fd_, -1); }
  void reset();

 private:
  int fd_ = -1;
};

struct HostPort {
  std::string host;  // empty: all interfaces (for listening)
  std::string port;
};

// "HOST:PORT", "[IPV6]:PORT", ":PORT". Throws std::invalid_argument when malformed.
HostPort split_host_port(const std::string& address);

// A non-blocking listening TCP socket. Throws std::runtime_error when it cannot listen.
UniqueFd listen_tcp(const HostPort& address, int backlog);
// The local port a socket is bound to.
unsigned short local_port(int fd);

// A connected, non-blocking TCP socket, or std::runtime_error when the deadline passes first.
UniqueFd connect_tcp(const HostPort& address, std::chrono::steady_clock::time_point deadline);

void set_nonblocking(int fd);

// Milliseconds left until `deadline` for poll(); 0 when past.
int poll_timeout_ms(std::chrono::steady_clock::time_point deadline);

}  // namespace primlabel::metrics::detail
