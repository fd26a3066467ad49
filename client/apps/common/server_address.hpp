#pragma once
// The --server value (or $PRIMLABEL_SERVER) as a gRPC target: HOST alone gets the server's
// default port, so "labeler" means labeler:50051 and never port 0.

#include <string>

namespace primlabel::client::tools {

// The port primlabel-server listens on by default (--listen 127.0.0.1:50051).
inline constexpr int kDefaultServerPort = 50051;

// "HOST" -> "HOST:50051", "[V6]" -> "[V6]:50051", a bare IPv6 address ("::1") -> "[::1]:50051";
// "HOST:PORT", "[V6]:PORT" and gRPC URIs ("dns:///h:p", "unix:/path", "ipv4:h:p", ...) as
// given. Throws std::invalid_argument naming the problem: empty, blanks, an empty or
// non-numeric port, a port outside 1..65535.
std::string server_address_with_port(const std::string& address);

}  // namespace primlabel::client::tools
