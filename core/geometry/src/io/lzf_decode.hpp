#pragma once
// LZF decompression for PCD binary_compressed data (PCL writes it with liblzf's lzf_compress):
// liblzf's lzf_decompress, with its errno outcomes as a status. A hand-written decoder with block
// copies was measured at 5.5 -> 3.1 ms a Kinect frame (2026-12-07) and not kept: the Debian
// library is the one to trust with hostile input.

#include <cstddef>

namespace primlabel::io_detail {

enum class LzfStatus {
  kOk,              // the whole input was decoded
  kOutputOverflow,  // the stream expands to more than out_size bytes (liblzf: E2BIG)
  kInvalid,         // a run past the input's end, or a reference before the output's start
};

struct LzfDecoded {
  LzfStatus status = LzfStatus::kOk;
  std::size_t produced = 0;  // bytes written to `out` (meaningful with kOk)
};

// Decodes `in_size` bytes of LZF data into out[0, out_size). Never reads or writes outside the
// two buffers, whatever the input.
LzfDecoded lzf_decode(const unsigned char* in, std::size_t in_size, unsigned char* out,
                      std::size_t out_size);

}  // namespace primlabel::io_detail
