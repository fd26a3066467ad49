#pragma once
// The labeling RPCs on gRPC's callback API, on raw messages (a malformed message gets an
// INVALID_ARGUMENT naming it instead of looking like the end of the stream). No thread per call:
// the reactions run on gRPC's threads, labeling on the Admission workers, timers on the one
// TimerService thread.
//
// Label, one reactor per call:
//   header (receiving slot) -> chunks until EndOfScan or half-close -> compute slot, label ->
//   LabelChunks -> LabelSummary -> OK.
// Every phase is bounded: --stream-idle-seconds between messages, --min-receive-bytes-per-second
// while receiving, --send-timeout-seconds per answer message, and the client's deadline or else
// --max-request-seconds for the whole call. Anything out of order ends the call with
// INVALID_ARGUMENT naming the message; any exception with INTERNAL; the server keeps serving.
//
// LabelCloud: one LabelCloudRequest answered by one LabelCloudResponse; an answer that would not
// fit the message limit is refused before labeling.

#include <grpcpp/server_context.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/server_callback.h>

#include "primlabel/rpc/auth.hpp"
#include "primlabel/service/service_environment.hpp"

namespace primlabel::rpc {

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* start_label_reactor(
    const service::ServiceEnvironment& env, const TokenAuth& auth,
    grpc::CallbackServerContext* context);

grpc::ServerUnaryReactor* start_label_cloud_reactor(const service::ServiceEnvironment& env,
                                                    const TokenAuth& auth,
                                                    grpc::CallbackServerContext* context,
                                                    const grpc::ByteBuffer* request,
                                                    grpc::ByteBuffer* response);

}  // namespace primlabel::rpc
