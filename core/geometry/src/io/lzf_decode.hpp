#pragma once
// LZF decompression for PCD binary_compressed data, the format liblzf's lzf_decompress reads
// (PCL writes it with lzf_compress). The stream decodes to the same bytes as with liblzf; it
// copies literal runs and back-references in 8- to 32-byte blocks where liblzf copies byte by
// byte, which matters for a 6 MB Kinect frame read on every labeling call.

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
