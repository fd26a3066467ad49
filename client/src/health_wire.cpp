#include "health_wire.hpp"

namespace primlabel::client::health_wire {

namespace {

void put_varint(std::string& out, std::uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<char>((v & 0x7F) | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<char>(v));
}

bool get_varint(std::string_view& in, std::uint64_t& v) {
  v = 0;
  for (int shift = 0; shift < 64 && !in.empty(); shift += 7) {
    const auto byte = static_cast<std::uint8_t>(in.front());
    in.remove_prefix(1);
    v |= static_cast<std::uint64_t>(byte & 0x7F) << shift;
    if (!(byte & 0x80)) return true;
  }
  return false;
}

}  // namespace

std::string encode_request(std::string_view service) {
  std::string out;
  if (service.empty()) return out;  // proto3 omits the default
  out.push_back(0x0A);              // field 1, length-delimited
  put_varint(out, service.size());
  out.append(service);
  return out;
}

std::optional<std::uint32_t> decode_status(std::string_view bytes) {
  std::uint32_t status = 0;  // absent = UNKNOWN
  while (!bytes.empty()) {
    std::uint64_t key = 0, value = 0;
    if (!get_varint(bytes, key)) return std::nullopt;
    switch (key & 7) {
      case 0:
        if (!get_varint(bytes, value)) return std::nullopt;
        if (key >> 3 == 1) status = static_cast<std::uint32_t>(value);
        break;
      case 1:
        if (bytes.size() < 8) return std::nullopt;
        bytes.remove_prefix(8);
        break;
      case 2:
        if (!get_varint(bytes, value) || value > bytes.size()) return std::nullopt;
        bytes.remove_prefix(value);
        break;
      case 5:
        if (bytes.size() < 4) return std::nullopt;
        bytes.remove_prefix(4);
        break;
      default:
        return std::nullopt;
    }
  }
  return status;
}

}  // namespace primlabel::client::health_wire
