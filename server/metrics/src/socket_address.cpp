#include "socket_address.hpp"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <stdexcept>

namespace primlabel::metrics::detail {
namespace {

using AddrInfoPtr = std::unique_ptr<addrinfo, decltype(&freeaddrinfo)>;

AddrInfoPtr resolve(const HostPort& address, bool passive) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV | (passive ? AI_PASSIVE : 0);
  addrinfo* result = nullptr;
  const char* host = address.host.empty() ? nullptr : address.host.c_str();
  const int rc = getaddrinfo(host, address.port.c_str(), &hints, &result);
  if (rc != 0)
    throw std::runtime_error("cannot resolve " + address.host + ":" + address.port + ": " +
                             gai_strerror(rc));
  return AddrInfoPtr(result, &freeaddrinfo);
}

std::string errno_text() { return std::strerror(errno); }

}  // namespace

UniqueFd& UniqueFd::operator=(UniqueFd&& other) noexcept {
  if (this != &other) {
    reset();
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

void UniqueFd::reset() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

HostPort split_host_port(const std::string& address) {
  HostPort result;
  std::string port;
  if (address.starts_with('[')) {
    const auto close = address.find(']');
    if (close == std::string::npos || close + 1 >= address.size() || address[close + 1] != ':')
      throw std::invalid_argument("malformed address '" + address + "' (expected [IPV6]:PORT)");
    result.host = address.substr(1, close - 1);
    port = address.substr(close + 2);
  } else {
    const auto colon = address.rfind(':');
    if (colon == std::string::npos || address.find(':') != colon)
      throw std::invalid_argument("malformed address '" + address + "' (expected HOST:PORT)");
    result.host = address.substr(0, colon);
    port = address.substr(colon + 1);
  }
  if (result.host == "*") result.host.clear();
  const bool numeric = !port.empty() && port.size() <= 5 &&
                       port.find_first_not_of("0123456789") == std::string::npos;
  if (!numeric || std::stoi(port) > 65535)
    throw std::invalid_argument("malformed port in address '" + address + "'");
  result.port = port;
  return result;
}

void set_nonblocking(int fd) {
  const int flags = fcntl(fd, F_GETFL, 0);
  if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0)
    throw std::runtime_error("fcntl(O_NONBLOCK): " + errno_text());
}

UniqueFd listen_tcp(const HostPort& address, int backlog) {
  const auto addresses = resolve(address, /*passive=*/true);
  std::string last_error = "no address";
  for (const addrinfo* ai = addresses.get(); ai; ai = ai->ai_next) {
    UniqueFd fd(socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol));
    if (fd.get() < 0) {
      last_error = errno_text();
      continue;
    }
    // A restarted server must be able to bind while old connections sit in TIME_WAIT.
    const int one = 1;
    setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (bind(fd.get(), ai->ai_addr, ai->ai_addrlen) == 0 && listen(fd.get(), backlog) == 0) {
      set_nonblocking(fd.get());
      return fd;
    }
    last_error = errno_text();
  }
  throw std::runtime_error("cannot listen on " + address.host + ":" + address.port + ": " +
                           last_error);
}

unsigned short local_port(int fd) {
  sockaddr_storage storage{};
  socklen_t length = sizeof storage;
  if (getsockname(fd, reinterpret_cast<sockaddr*>(&storage), &length) != 0)
    throw std::runtime_error("getsockname: " + errno_text());
  if (storage.ss_family == AF_INET6)
    return ntohs(reinterpret_cast<const sockaddr_in6*>(&storage)->sin6_port);
  return ntohs(reinterpret_cast<const sockaddr_in*>(&storage)->sin_port);
}

int poll_timeout_ms(std::chrono::steady_clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
      deadline - std::chrono::steady_clock::now());
  return left.count() > 0 ? static_cast<int>(left.count()) : 0;
}

UniqueFd connect_tcp(const HostPort& address, std::chrono::steady_clock::time_point deadline) {
  const auto addresses = resolve(address, /*passive=*/false);
  std::string last_error = "no address";
  for (const addrinfo* ai = addresses.get(); ai; ai = ai->ai_next) {
    UniqueFd fd(socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol));
    if (fd.get() < 0) {
      last_error = errno_text();
      continue;
    }
    set_nonblocking(fd.get());
    if (connect(fd.get(), ai->ai_addr, ai->ai_addrlen) == 0) return fd;
    if (errno != EINPROGRESS) {
      last_error = errno_text();
      continue;
    }
    pollfd waiting{fd.get(), POLLOUT, 0};
    const int ready = poll(&waiting, 1, poll_timeout_ms(deadline));
    if (ready == 0) throw std::runtime_error("timed out connecting to " + address.host);
    int error = 0;
    socklen_t length = sizeof error;
    if (ready > 0 && getsockopt(fd.get(), SOL_SOCKET, SO_ERROR, &error, &length) == 0 && error == 0)
      return fd;
    last_error = std::strerror(error ? error : errno);
  }
  throw std::runtime_error("cannot connect to " + address.host + ":" + address.port + ": " +
                           last_error);
}

}  // namespace primlabel::metrics::detail
