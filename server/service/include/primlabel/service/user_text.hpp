#pragma once
// Strings a client chose (model names, versions, scan ids) as they may appear in a status
// message, a log line or a metric: at most kMaxUserText bytes, control bytes shown as '?', and a
// cut one says how long it was. A 4 MB scan id must not become a 4 MB log line.

#include <cstddef>
#include <string>
#include <string_view>

namespace primlabel::service {

inline constexpr std::size_t kMaxUserText = 200;

inline std::string user_text(std::string_view text, std::size_t max_bytes = kMaxUserText) {
  const bool cut = text.size() > max_bytes;
  std::string out;
  out.reserve(std::min(text.size(), max_bytes) + 32);
  for (std::size_t i = 0; i < text.size() && i < max_bytes; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    out.push_back(c < 0x20 || c == 0x7f ? '?' : char(c));
  }
  if (cut) out += "...(" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace primlabel::service
