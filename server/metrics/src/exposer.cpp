#include "primlabel/metrics/exposer.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <list>
#include <stdexcept>

#include "http_request_reader.hpp"
#include "primlabel/metrics/text_format.hpp"
#include "socket_address.hpp"

namespace primlabel::metrics {
namespace {

using Clock = std::chrono::steady_clock;
using detail::HttpRequest;
using detail::HttpRequestReader;
using detail::UniqueFd;

constexpr std::size_t kMaxConnections = 64;
constexpr auto kIdleTimeout = std::chrono::seconds(60);
constexpr int kPollIntervalMs = 1000;  // how often idle connections are checked

struct Connection {
  explicit Connection(int accepted) : fd(accepted) {}

  UniqueFd fd;
  HttpRequestReader reader;
  std::string output;  // response bytes not yet sent
  std::size_t output_sent = 0;
  bool close_after_output = false;  // Connection: close, HTTP/1.0 or an error
  bool peer_done = false;           // the client will send nothing more
  Clock::time_point last_activity = Clock::now();

  bool output_pending() const { return output_sent < output.size(); }
};

const char* reason_phrase(int status) {
  switch (status) {
    case 200:
      return "OK";
    case 400:
      return "Bad Request";
    case 404:
      return "Not Found";
    case 405:
      return "Method Not Allowed";
    case 431:
      return "Request Header Fields Too Large";
    case 500:
      return "Internal Server Error";
    case 501:
      return "Not Implemented";
    case 505:
      return "HTTP Version Not Supported";
  }
  return "Error";
}

std::string http_response(int status, std::string_view content_type, const std::string& body,
                          bool keep_alive, bool head_only, std::string_view extra_headers = {}) {
  std::string out = "HTTP/1.1 " + std::to_string(status) + " " + reason_phrase(status) + "\r\n";
  out += "Content-Type: ";
  out += content_type;
  out += "\r\nContent-Length: " + std::to_string(body.size()) + "\r\n";
  out += keep_alive ? "Connection: keep-alive\r\n" : "Connection: close\r\n";
  out += extra_headers;
  out += "\r\n";
  if (!head_only) out += body;
  return out;
}

}  // namespace

Exposer::Exposer(const std::string& bind_address) {
  auto listener = detail::listen_tcp(detail::split_host_port(bind_address), 128);
  port_ = detail::local_port(listener.get());
  int wake[2];
  if (pipe2(wake, O_CLOEXEC | O_NONBLOCK) != 0)
    throw std::runtime_error(std::string("pipe2: ") + std::strerror(errno));
  listen_fd_ = listener.release();
  wake_read_fd_ = wake[0];
  wake_write_fd_ = wake[1];
  thread_ = std::thread([this] { serve(); });
}

Exposer::~Exposer() {
  const char stop = 1;
  // The pipe is empty and non-blocking, so this write succeeds at once.
  [[maybe_unused]] const auto written = ::write(wake_write_fd_, &stop, 1);
  thread_.join();
  ::close(listen_fd_);
  ::close(wake_read_fd_);
  ::close(wake_write_fd_);
}

void Exposer::RegisterCollectable(const std::weak_ptr<Registry>& registry) {
  std::lock_guard lock(collectables_mutex_);
  collectables_.push_back(registry);
}

void Exposer::RemoveCollectable(const std::weak_ptr<Registry>& registry) {
  std::lock_guard lock(collectables_mutex_);
  std::erase_if(collectables_, [&](const std::weak_ptr<Registry>& held) {
    return !held.owner_before(registry) && !registry.owner_before(held);
  });
}

std::string Exposer::scrape() {
  std::vector<std::shared_ptr<Registry>> live;
  {
    std::lock_guard lock(collectables_mutex_);
    std::erase_if(collectables_,
                  [](const std::weak_ptr<Registry>& held) { return held.expired(); });
    for (const auto& held : collectables_)
      if (auto registry = held.lock()) live.push_back(std::move(registry));
  }
  std::string text;
  for (const auto& registry : live) text += registry->Serialize();
  return text;
}

void Exposer::serve() {
  std::list<Connection> connections;  // std::list: stable while we index pollfds alongside
  std::vector<pollfd> fds;
  std::vector<Connection*> polled;

  // Answers every complete request buffered on `c`, but only while nothing is waiting to be
  // sent: a client pipelining many requests without reading cannot grow our memory.
  auto answer_requests = [&](Connection& c) {
    while (!c.output_pending() && !c.close_after_output) {
      auto result = c.reader.next();
      if (result.outcome == HttpRequestReader::Outcome::kIncomplete) return;
      c.output.clear();
      c.output_sent = 0;
      if (result.outcome == HttpRequestReader::Outcome::kError) {
        c.output = http_response(result.error_status, "text/plain; charset=utf-8",
                                 result.error + "\n", /*keep_alive=*/false, false);
        c.close_after_output = true;
        return;
      }
      const HttpRequest& request = result.request;
      const bool head = request.method == "HEAD";
      c.close_after_output = !request.keep_alive;
      if (request.method != "GET" && !head) {
        c.output = http_response(405, "text/plain; charset=utf-8", "method not allowed\n",
                                 request.keep_alive, false, "Allow: GET, HEAD\r\n");
      } else if (request.path() != "/metrics") {
        c.output = http_response(404, "text/plain; charset=utf-8", "not found; try /metrics\n",
                                 request.keep_alive, head);
      } else {
        try {
          c.output = http_response(200, kTextContentType, scrape(), request.keep_alive, head);
        } catch (const std::exception& e) {
          c.output = http_response(500, "text/plain; charset=utf-8", e.what() + std::string("\n"),
                                   request.keep_alive, head);
        }
      }
    }
  };

  while (true) {
    fds.clear();
    polled.clear();
    fds.push_back({wake_read_fd_, POLLIN, 0});
    fds.push_back(
        {listen_fd_, static_cast<short>(connections.size() < kMaxConnections ? POLLIN : 0), 0});
    for (auto& c : connections) {
      short events = 0;
      if (c.output_pending()) events |= POLLOUT;
      if (!c.peer_done && !c.output_pending() && !c.close_after_output) events |= POLLIN;
      fds.push_back({c.fd.get(), events, 0});
      polled.push_back(&c);
    }
    const int ready = poll(fds.data(), fds.size(), kPollIntervalMs);
    if (ready < 0 && errno != EINTR) break;  // cannot happen with valid fds; stop serving
    if (fds[0].revents & POLLIN) return;     // ~Exposer

    const auto now = Clock::now();
    for (std::size_t i = 0; i < polled.size(); ++i) {
      Connection& c = *polled[i];
      const short revents = fds[i + 2].revents;
      if (revents & (POLLERR | POLLNVAL)) {
        c.close_after_output = true;
        c.output.clear();
        c.output_sent = 0;
        continue;
      }
      if (revents & (POLLIN | POLLHUP)) {
        char buffer[4096];
        const ssize_t n = recv(c.fd.get(), buffer, sizeof buffer, 0);
        if (n > 0) {
          c.reader.feed(std::string_view(buffer, static_cast<std::size_t>(n)));
          c.last_activity = now;
        } else if (n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
          c.peer_done = true;  // still answer what it sent before closing its side
        }
      }
      if (revents & POLLOUT) {
        const ssize_t n = send(c.fd.get(), c.output.data() + c.output_sent,
                               c.output.size() - c.output_sent, MSG_NOSIGNAL);
        if (n > 0) {
          c.output_sent += static_cast<std::size_t>(n);
          c.last_activity = now;
        } else if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
          c.close_after_output = true;  // the peer is gone: drop what is left
          c.output.clear();
          c.output_sent = 0;
        }
      }
      answer_requests(c);
    }
    std::erase_if(connections, [&](const Connection& c) {
      if (c.output_pending()) return now - c.last_activity > kIdleTimeout;
      return c.close_after_output || c.peer_done || now - c.last_activity > kIdleTimeout;
    });

    if (fds[1].revents & POLLIN) {
      while (connections.size() < kMaxConnections) {
        const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) break;  // EAGAIN: no more waiting; other errors: the client went away
        connections.emplace_back(fd);
      }
    }
  }
}

}  // namespace primlabel::metrics
