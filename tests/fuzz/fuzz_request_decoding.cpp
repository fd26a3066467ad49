// libFuzzer target: the server's decoding of Label / LabelCloud requests, parsed by protobuf from
// the fuzz bytes. Input: one selector byte, then
//   even: a serialized LabelCloudRequest (the unary call);
//   odd:  a Label stream, messages framed as [uint16 little-endian length][serialized
//         LabelRequest], the first of which must carry the header (as the server requires).
// Must not crash, throw or allocate without bound (libFuzzer's -malloc_limit_mb catches that).

#include <google/protobuf/stubs/logging.h>

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include "request_decoding.hpp"

namespace {

constexpr std::size_t kMaxStreamMessages = 256;

void decode_unary(const std::uint8_t* data, std::size_t size) {
  primlabel::v1::LabelCloudRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size)) || !request.has_header()) return;
  primlabel::fuzz::decode_scan(request.header(), {&request.points()},
                               primlabel::fuzz::server_default_limits());
}

void decode_stream(const std::uint8_t* data, std::size_t size) {
  std::deque<primlabel::v1::LabelRequest> messages;  // stable addresses for the chunk pointers
  std::size_t at = 0;
  while (at + 2 <= size && messages.size() < kMaxStreamMessages) {
    const std::size_t length = data[at] | (std::size_t{data[at + 1]} << 8);
    at += 2;
    if (length > size - at) return;  // a stream cut inside a message
    if (!messages.emplace_back().ParseFromArray(data + at, static_cast<int>(length))) return;
    at += length;
  }
  if (messages.empty() || !messages.front().has_header()) return;
  std::vector<const primlabel::v1::PointChunk*> chunks;
  for (std::size_t i = 1; i < messages.size(); ++i) {
    if (messages[i].has_end()) break;
    if (!messages[i].has_chunk()) return;  // the server refuses a second header, or nothing
    chunks.push_back(&messages[i].chunk());
  }
  primlabel::fuzz::decode_scan(messages.front().header(), chunks,
                               primlabel::fuzz::server_default_limits());
}

}  // namespace

// Protobuf logs every invalid UTF-8 string it parses; the fuzzer's output is for findings.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  google::protobuf::SetLogHandler(nullptr);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  if (data[0] % 2 == 0) {
    decode_unary(data + 1, size - 1);
  } else {
    decode_stream(data + 1, size - 1);
  }
  return 0;
}
