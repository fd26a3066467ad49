// The LZF decoder of PCD binary_compressed (core/geometry/src/io/lzf_decode.hpp, over liblzf)
// against a byte-by-byte reference decoder of the format: back-references of every short period,
// near the end of the output and far from it, and the three ways a stream can be wrong (each
// with the status the PCD reader turns into its message).

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "lzf_decode.hpp"

namespace primlabel::io_detail {
namespace {

using Bytes = std::vector<unsigned char>;

// The format as its description gives it, one byte at a time.
Bytes reference_decode(const Bytes& in) {
  Bytes out;
  for (std::size_t i = 0; i < in.size();) {
    const unsigned ctrl = in[i++];
    if (ctrl < 32) {
      for (unsigned k = 0; k <= ctrl; ++k) out.push_back(in[i++]);
      continue;
    }
    std::size_t length = ctrl >> 5;
    if (length == 7) length += in[i++];
    const std::size_t distance = ((ctrl & 31u) << 8) + in[i++] + 1;
    for (std::size_t k = 0; k < length + 2; ++k) out.push_back(out[out.size() - distance]);
  }
  return out;
}

void add_literals(Bytes& stream, const Bytes& bytes) {
  for (std::size_t i = 0; i < bytes.size(); i += 32) {
    const std::size_t run = std::min<std::size_t>(32, bytes.size() - i);
    stream.push_back(static_cast<unsigned char>(run - 1));
    stream.insert(stream.end(), bytes.begin() + std::ptrdiff_t(i),
                  bytes.begin() + std::ptrdiff_t(i + run));
  }
}

// A back-reference of `length` (3..264) bytes from `distance` (1..8192) bytes back.
void add_reference(Bytes& stream, std::size_t distance, std::size_t length) {
  const std::size_t stored = distance - 1, extra = length - 2;
  if (extra < 7) {
    stream.push_back(static_cast<unsigned char>((extra << 5) | (stored >> 8)));
  } else {
    stream.push_back(static_cast<unsigned char>((7u << 5) | (stored >> 8)));
    stream.push_back(static_cast<unsigned char>(extra - 7));
  }
  stream.push_back(static_cast<unsigned char>(stored & 0xff));
}

Bytes random_bytes(std::size_t n, std::mt19937& rng) {
  Bytes out(n);
  for (unsigned char& b : out) b = static_cast<unsigned char>(rng());
  return out;
}

void expect_decodes_like_reference(const Bytes& stream) {
  const Bytes expected = reference_decode(stream);
  Bytes out(expected.size());
  const LzfDecoded decoded = lzf_decode(stream.data(), stream.size(), out.data(), out.size());
  ASSERT_EQ(decoded.status, LzfStatus::kOk);
  ASSERT_EQ(decoded.produced, expected.size());
  EXPECT_EQ(out, expected);
}

TEST(LzfDecode, EveryShortPeriodAndLengthInTheMiddleAndAtTheEnd) {
  std::mt19937 rng(5);
  for (std::size_t distance = 1; distance <= 20; ++distance)
    for (std::size_t length : {3, 7, 8, 9, 15, 16, 17, 40, 263, 264}) {
      Bytes middle;  // the reference is followed by more data: blocks may overshoot
      add_literals(middle, random_bytes(24, rng));
      add_reference(middle, distance, length);
      add_literals(middle, random_bytes(300, rng));
      expect_decodes_like_reference(middle);

      Bytes end;  // the reference ends the output: no byte may be written past it
      add_literals(end, random_bytes(24, rng));
      add_reference(end, distance, length);
      expect_decodes_like_reference(end);
    }
}

TEST(LzfDecode, LongDistancesAndLiteralRunsOfEveryLength) {
  std::mt19937 rng(6);
  Bytes stream;
  add_literals(stream, random_bytes(9000, rng));
  for (std::size_t distance : {8, 9, 100, 4096, 8192}) add_reference(stream, distance, 100);
  for (std::size_t run = 1; run <= 32; ++run) add_literals(stream, random_bytes(run, rng));
  expect_decodes_like_reference(stream);
}

TEST(LzfDecode, MoreOutputThanRoomIsAnOverflow) {
  Bytes stream;
  add_literals(stream, Bytes(10, 7));
  add_reference(stream, 1, 20);
  Bytes out(29);
  EXPECT_EQ(lzf_decode(stream.data(), stream.size(), out.data(), out.size()).status,
            LzfStatus::kOutputOverflow);
  out.resize(5);
  EXPECT_EQ(lzf_decode(stream.data(), stream.size(), out.data(), out.size()).status,
            LzfStatus::kOutputOverflow);
}

TEST(LzfDecode, AReferenceBeforeTheStartOrARunPastTheInputIsInvalid) {
  Bytes before;
  add_literals(before, Bytes(3, 1));
  add_reference(before, 4, 3);
  Bytes out(100);
  EXPECT_EQ(lzf_decode(before.data(), before.size(), out.data(), out.size()).status,
            LzfStatus::kInvalid);

  const Bytes truncated_literal = {5, 1, 2};  // 6 literal bytes announced, 2 present
  EXPECT_EQ(
      lzf_decode(truncated_literal.data(), truncated_literal.size(), out.data(), out.size()).status,
      LzfStatus::kInvalid);

  Bytes truncated_reference;
  add_literals(truncated_reference, Bytes(4, 1));
  truncated_reference.push_back(0xe0);  // a long reference whose length and distance are cut off
  EXPECT_EQ(
      lzf_decode(truncated_reference.data(), truncated_reference.size(), out.data(), out.size())
          .status,
      LzfStatus::kInvalid);
}

TEST(LzfDecode, AShortStreamReportsWhatItProduced) {
  Bytes stream;
  add_literals(stream, Bytes(10, 3));
  Bytes out(50);
  const LzfDecoded decoded = lzf_decode(stream.data(), stream.size(), out.data(), out.size());
  EXPECT_EQ(decoded.status, LzfStatus::kOk);
  EXPECT_EQ(decoded.produced, 10u);
}

}  // namespace
}  // namespace primlabel::io_detail
