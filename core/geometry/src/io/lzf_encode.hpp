#pragma once
// LZF compression of PCD binary_compressed planes: one stream, as PCL writes it (liblzf's
// lzf_compress), or independent streams of `segment_bytes` each, compressed in parallel and
// concatenated, which decode as one stream (CloudWriteOptions in cloud_io.hpp).

#include <cstddef>

namespace primlabel::io_detail {

// The bytes lzf_encode may write for `size` input bytes: LZF's worst-case expansion, per segment.
std::size_t lzf_encode_capacity(std::size_t size, std::size_t segment_bytes);

// Compresses in[0, size) to `out` (room for lzf_encode_capacity bytes) as one stream
// (segment_bytes 0, or not less than size) or as segments on `threads` threads (0: OpenMP's
// default). Returns the bytes written; 0 for a failure (or an empty input).
std::size_t lzf_encode(const unsigned char* in, std::size_t size, std::size_t segment_bytes,
                       int threads, unsigned char* out);

}  // namespace primlabel::io_detail
