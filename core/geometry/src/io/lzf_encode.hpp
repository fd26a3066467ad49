#pragma once
// LZF compression of PCD binary_compressed planes: one stream, as PCL writes it (liblzf's
// lzf_compress), or independent streams compressed in parallel and concatenated, which decode
// as one stream (CloudWriteOptions in cloud_io.hpp).

#include <cstddef>
#include <functional>
#include <vector>

namespace primlabel::io_detail {

// The bytes an LZF stream of `size` input bytes may take: LZF's worst-case expansion.
std::size_t lzf_stream_capacity(std::size_t size);

// Compresses in[0, size) to `out` (room for lzf_stream_capacity(size)) as one stream. Returns
// the bytes written; 0 for a failure (or an empty input).
std::size_t lzf_encode(const unsigned char* in, std::size_t size, unsigned char* out);

// One segment of the data: `bytes` bytes that source(scratch) provides, either where they
// already are (returning a pointer to them) or copied into `scratch` (room for `bytes`).
struct LzfSegment {
  std::size_t bytes = 0;
  std::function<const unsigned char*(unsigned char* scratch)> source;
};

// The room lzf_encode_segments needs at `out`: each segment's worst case.
std::size_t lzf_segments_capacity(const std::vector<LzfSegment>& segments);

// Compresses each segment as a stream of its own on `threads` threads (0: OpenMP's default) and
// writes them to `out` one after another, in order. Returns the bytes written; 0 for a failure.
std::size_t lzf_encode_segments(const std::vector<LzfSegment>& segments, int threads,
                                unsigned char* out);

}  // namespace primlabel::io_detail
