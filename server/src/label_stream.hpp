#pragma once
// The streaming Label RPC as a state machine over raw messages:
//   expect header -> (admitted) receive chunks -> end of scan (or half-close) -> label -> send
//   chunks -> summary.
// Anything out of order (no header, a second header, an empty or malformed message, bad chunk)
// ends the call with INVALID_ARGUMENT naming the message; the server keeps serving.

#include <grpcpp/server_context.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/sync_stream.h>

#include "service_environment.hpp"

namespace primlabel::server {

using RawStream = grpc::ServerReaderWriter<grpc::ByteBuffer, grpc::ByteBuffer>;

grpc::Status serve_label_stream(const ServiceEnvironment& env, grpc::ServerContext& context,
                                RawStream& stream);

// LabelCloud: the same, for one LabelCloudRequest answered by one LabelCloudResponse.
grpc::Status serve_label_cloud(const ServiceEnvironment& env, grpc::ServerContext& context,
                               RawStream& stream);

}  // namespace primlabel::server
