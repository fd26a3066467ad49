#include "primlabel/scrape/http_fetch.hpp"

#include <curl/curl.h>

#include <memory>
#include <mutex>
#include <stdexcept>

namespace primlabel::scrape {
namespace {

// curl_global_init is not thread-safe in every libcurl; run it once, before any handle exists.
void init_curl_once() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (curl_global_init(CURL_GLOBAL_DEFAULT) != CURLE_OK)
      throw std::runtime_error("libcurl: curl_global_init failed");
  });
}

struct Body {
  std::string text;
  std::size_t max_bytes = 0;
  bool too_large = false;
};

std::size_t append_body(char* data, std::size_t size, std::size_t count, void* user) {
  auto& body = *static_cast<Body*>(user);
  const std::size_t bytes = size * count;
  if (bytes > body.max_bytes - body.text.size()) {
    body.too_large = true;
    return 0;  // makes libcurl stop with CURLE_WRITE_ERROR
  }
  body.text.append(data, bytes);
  return bytes;
}

struct CurlDeleter {
  void operator()(CURL* curl) const { curl_easy_cleanup(curl); }
};

}  // namespace

std::string fetch_text(const std::string& url, const FetchLimits& limits) {
  const auto fail = [&url](const std::string& why) -> std::runtime_error {
    return std::runtime_error("GET " + url + ": " + why);
  };
  if (!url.starts_with("http://") && !url.starts_with("https://"))
    throw fail("not an http:// or https:// URL");
  init_curl_once();
  const std::unique_ptr<CURL, CurlDeleter> curl(curl_easy_init());
  if (!curl) throw fail("libcurl: curl_easy_init failed");
  Body body;
  body.max_bytes = limits.max_bytes;
  char error[CURL_ERROR_SIZE] = "";
  CURL* handle = curl.get();
  curl_easy_setopt(handle, CURLOPT_URL, url.c_str());
  curl_easy_setopt(handle, CURLOPT_PROTOCOLS_STR, "http,https");
  curl_easy_setopt(handle, CURLOPT_NOSIGNAL, 1L);  // no SIGALRM for timeouts in a threaded tool
  curl_easy_setopt(handle, CURLOPT_TIMEOUT_MS, static_cast<long>(limits.timeout_ms));
  curl_easy_setopt(handle, CURLOPT_ERRORBUFFER, error);
  curl_easy_setopt(handle, CURLOPT_WRITEFUNCTION, append_body);
  curl_easy_setopt(handle, CURLOPT_WRITEDATA, &body);
  // Bodies may come gzip-compressed (prometheus-cpp compresses when asked).
  curl_easy_setopt(handle, CURLOPT_ACCEPT_ENCODING, "");
  const CURLcode code = curl_easy_perform(handle);
  if (body.too_large)
    throw fail("response larger than " + std::to_string(limits.max_bytes) + " bytes");
  if (code != CURLE_OK) throw fail(error[0] ? error : curl_easy_strerror(code));
  long status = 0;
  curl_easy_getinfo(handle, CURLINFO_RESPONSE_CODE, &status);
  if (status != 200) throw fail("HTTP status " + std::to_string(status));
  return std::move(body.text);
}

}  // namespace primlabel::scrape
