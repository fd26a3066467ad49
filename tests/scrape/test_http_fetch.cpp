// GET with libcurl against prometheus-cpp's Exposer on 127.0.0.1 (ephemeral ports): the body,
// and errors naming the URL and the reason, within bounded time and memory.

#include <gtest/gtest.h>
#include <prometheus/counter.h>
#include <prometheus/exposer.h>
#include <prometheus/registry.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "primlabel/scrape/exposition_parser.hpp"
#include "primlabel/scrape/http_fetch.hpp"

namespace primlabel::scrape {
namespace {

class Served {
 public:
  Served() : exposer_("127.0.0.1:0"), registry_(std::make_shared<prometheus::Registry>()) {
    prometheus::BuildCounter()
        .Name("hits_total")
        .Register(*registry_)
        .Add({{"a", "b"}})
        .Increment(3);
    exposer_.RegisterCollectable(registry_);
  }
  std::string url(const std::string& path = "/metrics") const {
    return "http://127.0.0.1:" + std::to_string(exposer_.GetListeningPorts().at(0)) + path;
  }

 private:
  prometheus::Exposer exposer_;
  std::shared_ptr<prometheus::Registry> registry_;
};

// The message of the std::runtime_error that fetch_text throws ("" when it does not throw).
std::string fetch_error(const std::string& url, const FetchLimits& limits = {}) {
  try {
    fetch_text(url, limits);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(HttpFetch, ReadsAMetricsEndpoint) {
  Served served;
  const auto samples = parse_exposition(fetch_text(served.url()));
  EXPECT_EQ(sum_samples(samples, "hits_total", {{"a", "b"}}), 3.0);
}

TEST(HttpFetch, ErrorsNameTheUrlAndTheReason) {
  Served served;
  const std::string missing = served.url("/nothing-here");
  const std::string not_found = fetch_error(missing);
  EXPECT_EQ(not_found.rfind("GET " + missing + ": ", 0), 0u) << not_found;
  EXPECT_NE(not_found.find("404"), std::string::npos) << not_found;

  EXPECT_NE(fetch_error(served.url(), {.max_bytes = 10}).find("larger than 10 bytes"),
            std::string::npos);
  EXPECT_NE(fetch_error("ftp://127.0.0.1/metrics").find("not an http:// or https:// URL"),
            std::string::npos);
  EXPECT_NE(fetch_error("http://").find("GET http://: "), std::string::npos);

  std::string closed_url;
  { closed_url = Served().url(); }  // nobody listens there any more
  const std::string refused = fetch_error(closed_url, {.timeout_ms = 2000});
  EXPECT_EQ(refused.rfind("GET " + closed_url + ": ", 0), 0u) << refused;
}

}  // namespace
}  // namespace primlabel::scrape
