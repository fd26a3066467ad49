#pragma once
// PNG files decoded back with libpng for the tests that write pictures (link PNG::PNG).

#include <png.h>

#include <algorithm>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace primlabel::test {

struct Decoded {
  int width = 0, height = 0;
  std::vector<std::uint32_t> rgb;
  std::uint32_t at(int x, int y) const { return rgb[std::size_t(y) * width + x]; }
  std::size_t count(std::uint32_t c, int x0, int y0, int x1, int y1) const {
    std::size_t n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) n += at(x, y) == c;
    return n;
  }
  // Pixels whose colour is mostly `channel` (16 red, 8 green, 0 blue): points are shaded at
  // silhouettes, so their colour is not always exact.
  std::size_t count_mostly(int channel, int x0, int y0, int x1, int y1) const {
    std::size_t n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const std::uint32_t c = at(x, y);
        int strongest = 0;
        for (int other : {0, 8, 16})
          if (other != channel && int(c >> other & 0xFF) > strongest)
            strongest = int(c >> other & 0xFF);
        n += int(c >> channel & 0xFF) > 100 && strongest < 60;
      }
    return n;
  }
  // Pixels whose colour differs from the same pixel of `other` (one missing there counts too).
  std::size_t pixels_differing_from(const Decoded& other) const {
    const std::size_t common = std::min(rgb.size(), other.rgb.size());
    std::size_t n = std::max(rgb.size(), other.rgb.size()) - common;
    for (std::size_t i = 0; i < common; ++i) n += rgb[i] != other.rgb[i];
    return n;
  }
  std::size_t distinct_colors() const {
    return std::set<std::uint32_t>(rgb.begin(), rgb.end()).size();
  }
};

// Width 0 when the file does not decode.
inline Decoded decode_png(const std::string& path) {
  Decoded out;
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return out;
  image.format = PNG_FORMAT_RGB;
  std::vector<png_byte> bytes(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, bytes.data(), 0, nullptr)) return out;
  out.width = int(image.width);
  out.height = int(image.height);
  for (std::size_t i = 0; i < bytes.size(); i += 3)
    out.rgb.push_back(std::uint32_t(bytes[i]) << 16 | std::uint32_t(bytes[i + 1]) << 8 |
                      bytes[i + 2]);
  return out;
}

}  // namespace primlabel::test
