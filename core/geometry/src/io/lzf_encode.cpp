#include "lzf_encode.hpp"

#include <lzf.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <vector>

#include "primlabel/geometry/parallel.hpp"

namespace primlabel::io_detail {

namespace {

std::size_t stream_capacity(std::size_t size) { return size + size / 16 + 64; }

std::size_t compress_stream(const unsigned char* in, std::size_t size, unsigned char* out) {
  if (size == 0) return 0;
  return lzf_compress(in, static_cast<unsigned>(size), out,
                      static_cast<unsigned>(stream_capacity(size)));
}

bool segmented(std::size_t size, std::size_t segment_bytes) {
  return segment_bytes > 0 && size > segment_bytes;
}

}  // namespace

std::size_t lzf_encode_capacity(std::size_t size, std::size_t segment_bytes) {
  if (!segmented(size, segment_bytes)) return stream_capacity(size);
  const std::size_t segments = (size + segment_bytes - 1) / segment_bytes;
  return size + size / 16 + 64 * segments;  // each segment's slack; the 1/16 sums to at most this
}

std::size_t lzf_encode(const unsigned char* in, std::size_t size, std::size_t segment_bytes,
                       int threads, unsigned char* out) {
  if (!segmented(size, segment_bytes)) return compress_stream(in, size, out);
  // Each segment into a buffer of its own (its size is known only once compressed), then
  // concatenated in order: a back-reference never reaches before its own segment's start.
  const std::size_t segments = (size + segment_bytes - 1) / segment_bytes;
  std::vector<std::unique_ptr<unsigned char[]>> compressed(segments);
  std::vector<std::size_t> compressed_size(segments, 0);
  detail::parallel_for(
      std::ptrdiff_t(segments), threads, detail::Schedule::Dynamic(1), [&](std::ptrdiff_t s) {
        const std::size_t first = std::size_t(s) * segment_bytes;
        const std::size_t bytes = std::min(segment_bytes, size - first);
        compressed[s] = std::make_unique_for_overwrite<unsigned char[]>(stream_capacity(bytes));
        compressed_size[s] = compress_stream(in + first, bytes, compressed[s].get());
      });
  std::size_t written = 0;
  for (std::size_t s = 0; s < segments; ++s) {
    if (compressed_size[s] == 0) return 0;
    std::memcpy(out + written, compressed[s].get(), compressed_size[s]);
    written += compressed_size[s];
  }
  return written;
}

}  // namespace primlabel::io_detail
