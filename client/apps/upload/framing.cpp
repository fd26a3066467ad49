#include "framing.hpp"

namespace primlabel::client::upload {

namespace {
constexpr std::string_view kMagic = "PLS1";
}

std::string encode_frame(std::string_view scan) {
  std::string out(kMagic);
  std::uint64_t n = scan.size();
  for (int i = 0; i < 8; ++i, n >>= 8) out.push_back(static_cast<char>(n & 0xFF));
  out.append(scan);
  return out;
}

std::optional<std::string> read_frame(std::istream& in, std::uint64_t max_bytes) {
  char head[12];
  in.read(head, 1);
  if (in.gcount() == 0) return std::nullopt;  // clean end
  in.read(head + 1, 11);
  if (in.gcount() != 11) throw FrameError("input ended inside a frame header");
  if (std::string_view(head, 4) != kMagic)
    throw FrameError("not a scan frame (expected the magic \"PLS1\")");
  std::uint64_t length = 0;
  for (int i = 11; i >= 4; --i) length = (length << 8) | static_cast<unsigned char>(head[i]);
  if (length > max_bytes)
    throw FrameError("frame of " + std::to_string(length) + " bytes is over the limit of " +
                     std::to_string(max_bytes));
  std::string scan(length, '\0');
  in.read(scan.data(), static_cast<std::streamsize>(length));
  if (static_cast<std::uint64_t>(in.gcount()) != length)
    throw FrameError("input ended inside a frame (" + std::to_string(in.gcount()) + " of " +
                     std::to_string(length) + " bytes)");
  return scan;
}

std::string scan_extension(std::string_view scan) {
  return scan.substr(0, 4) == "ply\n" || scan.substr(0, 5) == "ply\r\n" ? ".ply" : ".pcd";
}

}  // namespace primlabel::client::upload
