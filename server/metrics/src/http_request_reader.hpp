#pragma once
// Incremental HTTP/1.x request parsing for the exposer (internal to primlabel_metrics): bytes go
// in as they arrive, complete requests come out, pipelined ones in order.

#include <cstddef>
#include <map>
#include <string>
#include <string_view>

namespace primlabel::metrics::detail {

struct HttpRequest {
  std::string method;
  std::string target;                          // e.g. "/metrics?x=1"
  std::string version;                         // "HTTP/1.1" or "HTTP/1.0"
  std::map<std::string, std::string> headers;  // names lower-cased; repeated ones joined by ","
  bool keep_alive = true;
  std::string path() const { return target.substr(0, target.find('?')); }
};

class HttpRequestReader {
 public:
  static constexpr std::size_t kMaxHeaderBytes = 8192;

  enum class Outcome { kIncomplete, kRequest, kError };
  struct Result {
    Outcome outcome = Outcome::kIncomplete;
    HttpRequest request;   // kRequest
    int error_status = 0;  // kError: the status to answer with before closing
    std::string error;
  };

  void feed(std::string_view bytes) { buffer_.append(bytes); }
  // The next complete request (its body, if any, is consumed and dropped). After kError the
  // connection must be closed: the stream can no longer be framed.
  Result next();

 private:
  std::string buffer_;
  std::size_t body_bytes_to_skip_ = 0;
};

}  // namespace primlabel::metrics::detail
