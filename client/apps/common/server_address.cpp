#include "server_address.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <stdexcept>
#include <string_view>

namespace primlabel::client::tools {

namespace {

// gRPC's own target schemes; their addresses are gRPC's to parse.
bool is_grpc_uri(const std::string& address) {
  static constexpr std::array<std::string_view, 7> kSchemes = {
      "dns:", "unix:", "unix-abstract:", "ipv4:", "ipv6:", "vsock:", "xds:"};
  return std::any_of(kSchemes.begin(), kSchemes.end(),
                     [&](std::string_view s) { return address.starts_with(s); });
}

void check_port(const std::string& address, std::string_view port) {
  const auto fail = [&](const std::string& why) {
    return std::invalid_argument("server address '" + address + "': " + why);
  };
  if (port.empty()) throw fail("no port after ':' (give HOST or HOST:PORT)");
  if (port.size() > 5 ||
      !std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; }))
    throw fail("port '" + std::string(port) + "' is not a number");
  const int value = std::stoi(std::string(port));
  if (value < 1 || value > 65535) throw fail("port " + std::to_string(value) + " is not 1..65535");
}

}  // namespace

std::string server_address_with_port(const std::string& address) {
  if (address.empty()) throw std::invalid_argument("empty server address");
  if (std::any_of(address.begin(), address.end(),
                  [](char c) { return static_cast<unsigned char>(c) <= ' ' || c == 0x7f; }))
    throw std::invalid_argument("server address '" + address +
                                "' has blanks or control characters");
  if (is_grpc_uri(address)) return address;
  // A web URL: gRPC takes HOST:PORT, and "http://h:p" would otherwise read as an IPv6 address
  // and fail later, as a name lookup, after every retry.
  if (const auto scheme = address.find("://"); scheme != std::string::npos) {
    std::string rest = address.substr(scheme + 3);
    rest = rest.substr(0, rest.find('/'));
    throw std::invalid_argument("server address '" + address + "' is a URL; give HOST:PORT" +
                                (rest.empty() ? std::string() : " (e.g. '" + rest + "')"));
  }
  const std::string port_suffix = ":" + std::to_string(kDefaultServerPort);
  if (address.front() == '[') {
    const auto close = address.find(']');
    if (close == std::string::npos)
      throw std::invalid_argument("server address '" + address + "': no closing ']'");
    if (close + 1 == address.size()) return address + port_suffix;
    if (address[close + 1] != ':')
      throw std::invalid_argument("server address '" + address + "': expected ':PORT' after ']'");
    check_port(address, std::string_view(address).substr(close + 2));
    return address;
  }
  const auto colons = std::count(address.begin(), address.end(), ':');
  if (colons == 0) return address + port_suffix;
  if (colons > 1) {  // a bare IPv6 address: hex digits, colons and a dotted IPv4 tail
    if (!std::all_of(address.begin(), address.end(), [](char c) {
          return std::isxdigit(static_cast<unsigned char>(c)) || c == ':' || c == '.';
        }))
      throw std::invalid_argument("server address '" + address +
                                  "': more than one ':' but not an IPv6 address (give HOST:PORT, "
                                  "or [IPV6]:PORT)");
    return "[" + address + "]" + port_suffix;
  }
  const auto colon = address.find(':');
  if (colon == 0) throw std::invalid_argument("server address '" + address + "': no host");
  check_port(address, std::string_view(address).substr(colon + 1));
  return address;
}

}  // namespace primlabel::client::tools
