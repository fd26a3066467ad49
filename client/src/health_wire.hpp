#pragma once
// grpc.health.v1 HealthCheckRequest / HealthCheckResponse by hand: two one-field messages, so the
// client needs no copy of health.proto (whose generated code would clash with a server's copy in
// the same process).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace primlabel::client::health_wire {

// HealthCheckRequest { string service = 1; }
std::string encode_request(std::string_view service);

// HealthCheckResponse { ServingStatus status = 1; }; nothing when the bytes are malformed.
std::optional<std::uint32_t> decode_status(std::string_view bytes);

}  // namespace primlabel::client::health_wire
