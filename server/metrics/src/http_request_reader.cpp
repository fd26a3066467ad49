#include "http_request_reader.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>

namespace primlabel::metrics::detail {
namespace {

std::string lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

// True when the comma-separated header value holds `token` (case-insensitive).
bool has_token(const std::string& value, std::string_view token) {
  std::string_view rest = value;
  while (!rest.empty()) {
    const auto comma = rest.find(',');
    if (lower(trim(rest.substr(0, comma))) == token) return true;
    rest.remove_prefix(comma == std::string_view::npos ? rest.size() : comma + 1);
  }
  return false;
}

HttpRequestReader::Result error(int status, std::string message) {
  HttpRequestReader::Result result;
  result.outcome = HttpRequestReader::Outcome::kError;
  result.error_status = status;
  result.error = std::move(message);
  return result;
}

}  // namespace

HttpRequestReader::Result HttpRequestReader::next() {
  // Drop what is left of the previous request's body first.
  const std::size_t skipped = std::min(body_bytes_to_skip_, buffer_.size());
  buffer_.erase(0, skipped);
  body_bytes_to_skip_ -= skipped;
  if (body_bytes_to_skip_ > 0) return {};

  // Tolerate blank lines between requests (RFC 9112 2.2).
  while (buffer_.starts_with("\r\n")) buffer_.erase(0, 2);
  const auto header_end = buffer_.find("\r\n\r\n");
  if (header_end == std::string::npos) {
    if (buffer_.size() > kMaxHeaderBytes) return error(431, "request header too large");
    return {};
  }
  if (header_end > kMaxHeaderBytes) return error(431, "request header too large");
  const std::string head = buffer_.substr(0, header_end);
  buffer_.erase(0, header_end + 4);

  Result result;
  HttpRequest& request = result.request;
  std::string_view lines = head;
  const auto first_end = lines.find("\r\n");
  const std::string_view request_line = lines.substr(0, first_end);
  lines.remove_prefix(first_end == std::string_view::npos ? lines.size() : first_end + 2);

  const auto first_space = request_line.find(' ');
  const auto last_space = request_line.rfind(' ');
  if (first_space == std::string_view::npos || first_space == last_space)
    return error(400, "malformed request line");
  request.method = request_line.substr(0, first_space);
  request.target = request_line.substr(first_space + 1, last_space - first_space - 1);
  request.version = request_line.substr(last_space + 1);
  if (request.method.empty() || request.target.empty() ||
      request.target.find(' ') != std::string::npos)
    return error(400, "malformed request line");
  if (request.version != "HTTP/1.1" && request.version != "HTTP/1.0")
    return error(505, "unsupported HTTP version");

  while (!lines.empty()) {
    const auto end = lines.find("\r\n");
    const std::string_view line = lines.substr(0, end);
    lines.remove_prefix(end == std::string_view::npos ? lines.size() : end + 2);
    const auto colon = line.find(':');
    if (colon == std::string_view::npos || colon == 0 || line.front() == ' ' ||
        line.front() == '\t')
      return error(400, "malformed header line");
    const std::string name = lower(line.substr(0, colon));
    const std::string value(trim(line.substr(colon + 1)));
    auto [it, inserted] = request.headers.emplace(name, value);
    if (!inserted) it->second += "," + value;
  }

  if (request.headers.contains("transfer-encoding"))
    return error(501, "request bodies with Transfer-Encoding are not supported");
  if (auto it = request.headers.find("content-length"); it != request.headers.end()) {
    std::size_t length = 0;
    const auto& text = it->second;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), length);
    if (ec != std::errc() || end != text.data() + text.size())
      return error(400, "malformed Content-Length");
    body_bytes_to_skip_ = length;
  }

  const auto connection = request.headers.find("connection");
  const std::string connection_value =
      connection == request.headers.end() ? std::string() : connection->second;
  request.keep_alive = request.version == "HTTP/1.1" ? !has_token(connection_value, "close")
                                                     : has_token(connection_value, "keep-alive");
  result.outcome = Outcome::kRequest;
  return result;
}

}  // namespace primlabel::metrics::detail
