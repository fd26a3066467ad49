#include "primlabel/metrics/http_client.hpp"

#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <stdexcept>

#include "socket_address.hpp"

namespace primlabel::metrics {
namespace {

using Clock = std::chrono::steady_clock;

void wait_for(int fd, short events, Clock::time_point deadline, const std::string& what) {
  pollfd waiting{fd, events, 0};
  while (true) {
    const int ready = poll(&waiting, 1, detail::poll_timeout_ms(deadline));
    if (ready > 0) return;
    if (ready == 0) throw std::runtime_error("timed out " + what);
    if (errno != EINTR) throw std::runtime_error("poll failed " + what);
  }
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

// Undoes Transfer-Encoding: chunked (chunk extensions and trailers ignored).
std::string dechunk(const std::string& body) {
  std::string out;
  std::size_t pos = 0;
  while (true) {
    const auto line_end = body.find("\r\n", pos);
    if (line_end == std::string::npos) throw std::runtime_error("malformed chunked body");
    const std::size_t size = std::stoul(body.substr(pos, line_end - pos), nullptr, 16);
    pos = line_end + 2;
    if (size == 0) return out;
    if (pos + size > body.size()) throw std::runtime_error("truncated chunked body");
    out.append(body, pos, size);
    pos += size + 2;
  }
}

HttpResponse parse_response(const std::string& raw, bool head_request) {
  const auto header_end = raw.find("\r\n\r\n");
  if (header_end == std::string::npos) throw std::runtime_error("incomplete HTTP response");
  HttpResponse response;
  const std::string head = raw.substr(0, header_end);
  std::size_t pos = head.find("\r\n");
  const std::string status_line = head.substr(0, pos);
  if (!status_line.starts_with("HTTP/1.") || status_line.size() < 12)
    throw std::runtime_error("malformed HTTP status line '" + status_line + "'");
  response.status = std::stoi(status_line.substr(9, 3));
  while (pos != std::string::npos) {
    const std::size_t start = pos + 2;
    pos = head.find("\r\n", start);
    const std::string line = head.substr(start, pos == std::string::npos ? pos : pos - start);
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    response.headers[lower(line.substr(0, colon))] = value;
  }
  response.body = raw.substr(header_end + 4);
  if (head_request) {
    response.body.clear();  // a HEAD response announces a length but sends no body
  } else if (lower(response.headers["transfer-encoding"]) == "chunked") {
    response.body = dechunk(response.body);
  } else if (auto it = response.headers.find("content-length"); it != response.headers.end()) {
    const std::size_t length = std::stoul(it->second);
    if (response.body.size() < length) throw std::runtime_error("truncated HTTP response body");
    response.body.resize(length);
  }
  return response;
}

}  // namespace

HttpResponse http_request(const std::string& host_port, const std::string& path, int timeout_ms,
                          const std::string& method) {
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  const auto address = detail::split_host_port(host_port);
  const auto fd = detail::connect_tcp(address, deadline);
  const bool ipv6 = address.host.find(':') != std::string::npos;
  const std::string host = ipv6 ? "[" + address.host + "]" : address.host;
  const std::string request = method + " " + path + " HTTP/1.1\r\nHost: " + host + ":" +
                              address.port + "\r\nAccept: text/plain\r\nConnection: close\r\n\r\n";
  std::size_t sent = 0;
  while (sent < request.size()) {
    wait_for(fd.get(), POLLOUT, deadline, "sending to " + host_port);
    const ssize_t n = send(fd.get(), request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno != EAGAIN && errno != EINTR)
      throw std::runtime_error("send to " + host_port + " failed");
    if (n > 0) sent += static_cast<std::size_t>(n);
  }
  // We asked for Connection: close, so the response ends where the stream does.
  std::string raw;
  char buffer[16384];
  while (true) {
    wait_for(fd.get(), POLLIN, deadline, "reading from " + host_port);
    const ssize_t n = recv(fd.get(), buffer, sizeof buffer, 0);
    if (n == 0) break;
    if (n < 0 && errno != EAGAIN && errno != EINTR)
      throw std::runtime_error("read from " + host_port + " failed");
    if (n > 0) raw.append(buffer, static_cast<std::size_t>(n));
  }
  return parse_response(raw, method == "HEAD");
}

std::string http_get(const std::string& host_port, const std::string& path, int timeout_ms) {
  auto response = http_request(host_port, path, timeout_ms);
  if (response.status != 200)
    throw std::runtime_error("GET " + path + " from " + host_port + ": HTTP " +
                             std::to_string(response.status));
  return std::move(response.body);
}

}  // namespace primlabel::metrics
