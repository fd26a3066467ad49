#pragma once
// The stream format of `primlabel-upload --stdin`: scans back to back, each framed as
//   "PLS1"  4 bytes magic
//   length  uint64 little-endian, bytes of the scan
//   scan    the bytes of one PCD or PLY file
// End of input at a frame boundary ends the stream. `primlabel-upload --frame FILE...` writes
// this format, e.g. `primlabel-upload --frame *.pcd | ssh robot primlabel-upload --stdin ...`.

#include <cstdint>
#include <istream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace primlabel::client::upload {

class FrameError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string encode_frame(std::string_view scan);

// The next scan, or nothing at a clean end of input. Throws FrameError for a bad magic, a length
// over `max_bytes` or input ending inside a frame.
std::optional<std::string> read_frame(std::istream& in, std::uint64_t max_bytes);

// ".ply" when the bytes are a PLY file, else ".pcd".
std::string scan_extension(std::string_view scan);

}  // namespace primlabel::client::upload
