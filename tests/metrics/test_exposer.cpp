// The /metrics HTTP server over real sockets on 127.0.0.1 (ephemeral ports).

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "primlabel/metrics/metrics.hpp"

namespace primlabel::metrics {
namespace {

constexpr int kTimeoutMs = 5000;

struct Served {
  std::shared_ptr<Registry> registry = std::make_shared<Registry>();
  Exposer exposer{"127.0.0.1:0"};
  Counter* requests = nullptr;

  Served() {
    requests = &BuildCounter()
                    .Name("primlabel_requests_total")
                    .Help("Requests.")
                    .Register(*registry)
                    .Add({{"status", "OK"}});
    requests->Increment(7);
    exposer.RegisterCollectable(registry);
  }
  std::string address() const { return "127.0.0.1:" + std::to_string(exposer.port()); }
};

// A blocking client socket whose reads give up after kTimeoutMs, so no test can hang.
class RawConnection {
 public:
  explicit RawConnection(std::uint16_t port) : fd_(socket(AF_INET, SOCK_STREAM, 0)) {
    timeval timeout{kTimeoutMs / 1000, 0};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0)
      throw std::runtime_error("connect failed");
  }
  ~RawConnection() { close(fd_); }

  void send_text(const std::string& text) {
    ASSERT_EQ(send(fd_, text.data(), text.size(), MSG_NOSIGNAL), static_cast<ssize_t>(text.size()));
  }
  // Reads until `count` complete responses (framed by Content-Length) have arrived; returns them.
  std::vector<std::string> read_responses(int count) {
    std::vector<std::string> responses;
    while (static_cast<int>(responses.size()) < count) {
      const auto header_end = buffer_.find("\r\n\r\n");
      if (header_end != std::string::npos) {
        const auto length_at = buffer_.find("Content-Length: ");
        const std::size_t length = std::stoul(buffer_.substr(length_at + 16));
        const std::size_t total = header_end + 4 + length;
        if (buffer_.size() >= total) {
          responses.push_back(buffer_.substr(0, total));
          buffer_.erase(0, total);
          continue;
        }
      }
      if (!read_more()) break;
    }
    return responses;
  }
  // True when the server closed the connection (read returns 0) before the timeout.
  bool closed_by_server() { return !read_more() && last_read_ == 0; }

 private:
  bool read_more() {
    char chunk[4096];
    last_read_ = recv(fd_, chunk, sizeof chunk, 0);
    if (last_read_ <= 0) return false;
    buffer_.append(chunk, static_cast<std::size_t>(last_read_));
    return true;
  }
  int fd_;
  std::string buffer_;
  ssize_t last_read_ = -1;
};

TEST(Exposer, ServesMetricsWithTheTextContentType) {
  Served served;
  const auto response = http_request(served.address(), "/metrics", kTimeoutMs);
  EXPECT_EQ(response.status, 200);
  EXPECT_EQ(response.headers.at("content-type"), "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_NE(response.body.find("primlabel_requests_total{status=\"OK\"} 7\n"), std::string::npos)
      << response.body;
  // Values are read at scrape time.
  served.requests->Increment();
  const auto samples = parse_exposition(http_get(served.address(), "/metrics", kTimeoutMs));
  EXPECT_EQ(sum_samples(samples, "primlabel_requests_total"), 8);
  // A query string is ignored.
  EXPECT_EQ(http_request(served.address(), "/metrics?name[]=x", kTimeoutMs).status, 200);
}

TEST(Exposer, AnswersOtherPathsAndMethodsWithErrors) {
  Served served;
  EXPECT_EQ(http_request(served.address(), "/", kTimeoutMs).status, 404);
  EXPECT_EQ(http_request(served.address(), "/metricsx", kTimeoutMs).status, 404);
  EXPECT_THROW(http_get(served.address(), "/nope", kTimeoutMs), std::runtime_error);
  const auto post = http_request(served.address(), "/metrics", kTimeoutMs, "POST");
  EXPECT_EQ(post.status, 405);
  EXPECT_EQ(post.headers.at("allow"), "GET, HEAD");
  const auto head = http_request(served.address(), "/metrics", kTimeoutMs, "HEAD");
  EXPECT_EQ(head.status, 200);
  EXPECT_GT(std::stoul(head.headers.at("content-length")), 0u);
}

TEST(Exposer, KeepsConnectionsAliveAndAnswersPipelinedRequestsInOrder) {
  Served served;
  RawConnection connection(served.exposer.port());
  connection.send_text(
      "GET /metrics HTTP/1.1\r\nHost: x\r\n\r\n"
      "GET /other HTTP/1.1\r\nHost: x\r\n\r\n");
  auto responses = connection.read_responses(2);
  ASSERT_EQ(responses.size(), 2u);
  EXPECT_EQ(responses[0].rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << responses[0];
  EXPECT_NE(responses[0].find("Connection: keep-alive"), std::string::npos);
  EXPECT_NE(responses[0].find("primlabel_requests_total"), std::string::npos);
  EXPECT_EQ(responses[1].rfind("HTTP/1.1 404 Not Found\r\n", 0), 0u) << responses[1];

  // Same connection, now asking to close: one response, then the server closes.
  connection.send_text("GET /metrics HTTP/1.1\r\nConnection: close\r\n\r\n");
  responses = connection.read_responses(1);
  ASSERT_EQ(responses.size(), 1u);
  EXPECT_NE(responses[0].find("Connection: close"), std::string::npos);
  EXPECT_TRUE(connection.closed_by_server());
}

TEST(Exposer, Http10ClosesUnlessKeepAliveIsAsked) {
  Served served;
  {
    RawConnection connection(served.exposer.port());
    connection.send_text("GET /metrics HTTP/1.0\r\n\r\n");
    ASSERT_EQ(connection.read_responses(1).size(), 1u);
    EXPECT_TRUE(connection.closed_by_server());
  }
  RawConnection connection(served.exposer.port());
  connection.send_text("GET /metrics HTTP/1.0\r\nConnection: keep-alive\r\n\r\n");
  ASSERT_EQ(connection.read_responses(1).size(), 1u);
  connection.send_text("GET /metrics HTTP/1.0\r\nConnection: keep-alive\r\n\r\n");
  EXPECT_EQ(connection.read_responses(1).size(), 1u);
}

TEST(Exposer, MalformedRequestsGet400AndAClose) {
  Served served;
  RawConnection connection(served.exposer.port());
  connection.send_text("NONSENSE\r\n\r\n");
  const auto responses = connection.read_responses(1);
  ASSERT_EQ(responses.size(), 1u);
  EXPECT_EQ(responses[0].rfind("HTTP/1.1 400", 0), 0u) << responses[0];
  EXPECT_TRUE(connection.closed_by_server());

  RawConnection oversized(served.exposer.port());
  oversized.send_text("GET /metrics HTTP/1.1\r\nX: " + std::string(10000, 'a') + "\r\n\r\n");
  const auto too_large = oversized.read_responses(1);
  ASSERT_EQ(too_large.size(), 1u);
  EXPECT_EQ(too_large[0].rfind("HTTP/1.1 431", 0), 0u) << too_large[0];
}

TEST(Exposer, ServesConcurrentScrapersWhileAnotherClientStalls) {
  Served served;
  // A client that sent half a request and went quiet must not block anyone.
  RawConnection stalled(served.exposer.port());
  stalled.send_text("GET /metr");

  constexpr int kScrapers = 2;
  constexpr int kScrapesEach = 25;
  std::vector<int> successes(kScrapers, 0);
  std::vector<std::thread> scrapers;
  for (int s = 0; s < kScrapers; ++s) {
    scrapers.emplace_back([&, s] {
      for (int i = 0; i < kScrapesEach; ++i) {
        try {
          const auto samples = parse_exposition(http_get(served.address(), "/metrics", kTimeoutMs));
          if (sum_samples(samples, "primlabel_requests_total") >= 7) ++successes[s];
        } catch (const std::exception&) {
        }
      }
    });
  }
  for (auto& scraper : scrapers) scraper.join();
  for (int s = 0; s < kScrapers; ++s) EXPECT_EQ(successes[s], kScrapesEach);

  // The stalled client can still finish its request.
  stalled.send_text("ics HTTP/1.1\r\n\r\n");
  const auto responses = stalled.read_responses(1);
  ASSERT_EQ(responses.size(), 1u);
  EXPECT_EQ(responses[0].rfind("HTTP/1.1 200 OK", 0), 0u);
}

TEST(Exposer, MergesRegistriesAndForgetsDestroyedOnes) {
  Served served;
  auto second = std::make_shared<Registry>();
  BuildGauge().Name("second_gauge").Register(*second).Add({}).Set(3);
  served.exposer.RegisterCollectable(second);
  std::string body = http_get(served.address(), "/metrics", kTimeoutMs);
  EXPECT_NE(body.find("primlabel_requests_total"), std::string::npos);
  EXPECT_NE(body.find("second_gauge 3"), std::string::npos);

  second.reset();
  body = http_get(served.address(), "/metrics", kTimeoutMs);
  EXPECT_EQ(body.find("second_gauge"), std::string::npos);

  served.exposer.RemoveCollectable(served.registry);
  EXPECT_EQ(http_get(served.address(), "/metrics", kTimeoutMs), "");
}

TEST(Exposer, StopsCleanlyWithOpenConnections) {
  auto served = std::make_unique<Served>();
  const auto port = served->exposer.port();
  RawConnection idle(port);
  RawConnection mid_request(port);
  mid_request.send_text("GET /metrics HTTP/1.1\r\n");
  // Let the exposer accept both before it is destroyed.
  EXPECT_EQ(http_request(served->address(), "/metrics", kTimeoutMs).status, 200);
  served.reset();  // must return, closing both connections
  EXPECT_TRUE(idle.closed_by_server());
  EXPECT_TRUE(mid_request.closed_by_server());
}

TEST(Exposer, RejectsBadAddressesAndBusyPorts) {
  EXPECT_THROW(Exposer("no-port"), std::invalid_argument);
  EXPECT_THROW(Exposer("127.0.0.1:99999"), std::invalid_argument);
  EXPECT_THROW(Exposer("127.0.0.1:http"), std::invalid_argument);
  Exposer first("127.0.0.1:0");
  EXPECT_NE(first.port(), 0);
  EXPECT_THROW(Exposer("127.0.0.1:" + std::to_string(first.port())), std::runtime_error);
}

TEST(HttpClient, TimesOutOnASilentServer) {
  // A listening socket that never answers: the client must give up at its deadline.
  const int listener = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(listener, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  ASSERT_EQ(listen(listener, 4), 0);
  socklen_t length = sizeof address;
  getsockname(listener, reinterpret_cast<sockaddr*>(&address), &length);
  const std::string host_port = "127.0.0.1:" + std::to_string(ntohs(address.sin_port));
  EXPECT_THROW(http_get(host_port, "/metrics", 200), std::runtime_error);
  close(listener);
}

}  // namespace
}  // namespace primlabel::metrics
