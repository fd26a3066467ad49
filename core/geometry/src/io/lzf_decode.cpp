#include "lzf_decode.hpp"

#include <cstring>

namespace primlabel::io_detail {

namespace {

// A control byte below 32 starts a literal run of ctrl + 1 bytes; above, a back-reference of
// (ctrl >> 5) + 2 bytes (7: plus the next byte) at distance ((ctrl & 31) << 8) + next byte + 1.
constexpr unsigned kLiteralLimit = 1u << 5;
constexpr std::size_t kMaxLiteral = 32;
constexpr std::size_t kBlock = 8;

// Copies `length` bytes from `distance` bytes back in the output to `out`; the source may overlap
// the bytes being written (a run repeats its last `distance` bytes). `room` is how many bytes may
// be written at `out`, at least `length`.
inline void copy_match(unsigned char* out, std::size_t distance, std::size_t length,
                       std::size_t room) {
  const unsigned char* from = out - distance;
  if (room < length + kBlock) {  // near the end of the output: no block may run past it
    for (std::size_t i = 0; i < length; ++i) out[i] = from[i];
    return;
  }
  std::size_t done = 0;
  if (distance < kBlock) {
    // A short period: write one block byte by byte, then read from whole periods back, at least
    // a block away, where the bytes are final.
    for (; done < kBlock; ++done) out[done] = from[done];
    distance *= (kBlock + distance - 1) / distance;
    from = out - distance;
  }
  for (; done < length; done += kBlock) std::memcpy(out + done, from + done, kBlock);
}

}  // namespace

LzfDecoded lzf_decode(const unsigned char* in, std::size_t in_size, unsigned char* out,
                      std::size_t out_size) {
  const unsigned char* ip = in;
  const unsigned char* const in_end = in + in_size;
  unsigned char* op = out;
  unsigned char* const out_end = out + out_size;
  auto fail = [&](LzfStatus status) { return LzfDecoded{status, std::size_t(op - out)}; };

  while (ip < in_end) {
    const unsigned ctrl = *ip++;
    if (ctrl < kLiteralLimit) {
      const std::size_t length = ctrl + 1;
      if (length > std::size_t(out_end - op)) return fail(LzfStatus::kOutputOverflow);
      if (length > std::size_t(in_end - ip)) return fail(LzfStatus::kInvalid);
      // One fixed-size copy where both buffers have room for it; the bytes past the run are
      // overwritten by what follows.
      if (std::size_t(in_end - ip) >= kMaxLiteral && std::size_t(out_end - op) >= kMaxLiteral)
        std::memcpy(op, ip, kMaxLiteral);
      else
        std::memcpy(op, ip, length);
      op += length;
      ip += length;
      continue;
    }
    std::size_t length = ctrl >> 5;
    if (ip >= in_end) return fail(LzfStatus::kInvalid);
    if (length == 7) {
      length += *ip++;
      if (ip >= in_end) return fail(LzfStatus::kInvalid);
    }
    const std::size_t distance = (std::size_t(ctrl & 0x1f) << 8) + *ip++ + 1;
    length += 2;
    if (length > std::size_t(out_end - op)) return fail(LzfStatus::kOutputOverflow);
    if (distance > std::size_t(op - out)) return fail(LzfStatus::kInvalid);
    copy_match(op, distance, length, std::size_t(out_end - op));
    op += length;
  }
  return {LzfStatus::kOk, std::size_t(op - out)};
}

}  // namespace primlabel::io_detail
