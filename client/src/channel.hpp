#pragma once
// The gRPC channel a Client talks through: credentials (plaintext, TLS, mutual TLS) and the
// channel arguments (keepalive, reconnect backoff, message sizes) from ClientOptions.

#include <grpcpp/channel.h>

#include <memory>

#include "primlabel/client/client.hpp"

namespace primlabel::client {

// Throws ClientError(INVALID_ARGUMENT) when a TLS file cannot be read.
std::shared_ptr<grpc::Channel> make_channel(const ClientOptions& options);

}  // namespace primlabel::client
