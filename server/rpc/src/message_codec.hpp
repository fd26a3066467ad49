#pragma once
// Protobuf messages to and from the raw byte buffers of the labeling methods. Those methods
// take raw bytes so that a malformed message is answered with INVALID_ARGUMENT naming it,
// rather than read as the end of the stream.

#include <google/protobuf/message_lite.h>
#include <grpcpp/impl/codegen/proto_utils.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/proto_buffer_reader.h>
#include <grpcpp/support/proto_buffer_writer.h>

namespace primlabel::rpc {

inline bool parse_message(grpc::ByteBuffer& buffer, google::protobuf::MessageLite& message) {
  grpc::ProtoBufferReader reader(&buffer);
  return reader.status().ok() && message.ParseFromZeroCopyStream(&reader);
}

template <typename Message>
grpc::ByteBuffer serialize_message(const Message& message) {
  grpc::ByteBuffer buffer;
  bool own_buffer = false;
  grpc::SerializationTraits<Message>::Serialize(message, &buffer, &own_buffer);
  return buffer;
}

}  // namespace primlabel::rpc
