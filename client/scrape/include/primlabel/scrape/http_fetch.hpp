#pragma once
// Fetching one HTTP(S) resource with libcurl, enough to scrape a /metrics endpoint.

#include <cstddef>
#include <string>

namespace primlabel::scrape {

struct FetchLimits {
  int timeout_ms = 5000;             // the whole exchange, connecting included
  std::size_t max_bytes = 64 << 20;  // a larger body is an error, not an allocation
};

// The body of a GET of `url` (http:// or https:// only; redirects are not followed). Throws
// std::runtime_error naming the URL and the reason: malformed URL, connection failure, timeout,
// a status other than 200, or a body over limits.max_bytes. Safe to call from many threads.
std::string fetch_text(const std::string& url, const FetchLimits& limits = {});

}  // namespace primlabel::scrape
