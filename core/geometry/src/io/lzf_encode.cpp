#include "lzf_encode.hpp"

#include <lzf.h>

#include <algorithm>
#include <cstring>
#include <memory>

#include "primlabel/geometry/parallel.hpp"

namespace primlabel::io_detail {

std::size_t lzf_stream_capacity(std::size_t size) { return size + size / 16 + 64; }

std::size_t lzf_encode(const unsigned char* in, std::size_t size, unsigned char* out) {
  if (size == 0) return 0;
  return lzf_compress(in, static_cast<unsigned>(size), out,
                      static_cast<unsigned>(lzf_stream_capacity(size)));
}

std::size_t lzf_segments_capacity(const std::vector<LzfSegment>& segments) {
  std::size_t capacity = 0;
  for (const LzfSegment& segment : segments) capacity += lzf_stream_capacity(segment.bytes);
  return capacity;
}

std::size_t lzf_encode_segments(const std::vector<LzfSegment>& segments, int threads,
                                unsigned char* out) {
  // Each segment goes to a slot of its worst-case size inside `out` (only the bytes written are
  // touched), then the slots are closed up in order: no buffer per segment to fault in.
  std::vector<std::size_t> slot(segments.size(), 0), written(segments.size(), 0);
  std::size_t largest = 0;
  for (std::size_t s = 1; s < segments.size(); ++s)
    slot[s] = slot[s - 1] + lzf_stream_capacity(segments[s - 1].bytes);
  for (const LzfSegment& segment : segments) largest = std::max(largest, segment.bytes);

  // One scratch per thread for the segments that are gathered rather than in place.
  detail::parallel_for(
      std::ptrdiff_t(segments.size()), threads, detail::Schedule::Dynamic(1),
      [&] { return std::make_unique_for_overwrite<unsigned char[]>(largest); },
      [&](std::unique_ptr<unsigned char[]>& scratch, std::ptrdiff_t s) {
        const LzfSegment& segment = segments[s];
        written[s] = lzf_encode(segment.source(scratch.get()), segment.bytes, out + slot[s]);
      });
  std::size_t end = 0;
  for (std::size_t s = 0; s < segments.size(); ++s) {
    if (segments[s].bytes > 0 && written[s] == 0) return 0;
    std::memmove(out + end, out + slot[s], written[s]);
    end += written[s];
  }
  return end;
}

}  // namespace primlabel::io_detail
