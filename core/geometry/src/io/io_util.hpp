#pragma once
// Private helpers shared by the PCD and PLY readers/writers: whole-file reads, atomic writes,
// strict number parsing/formatting, and decoding of typed binary columns into PointCloud arrays.
// Header-only so each format stays in its own translation unit.

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <unordered_set>
#include <vector>

#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/cloud_io.hpp"

namespace primlabel::io_detail {

// PCD binary data is host-endian and PLY binary is converted to host order on read; both paths
// reinterpret bytes directly, which is only right on little-endian hosts.
static_assert(std::endian::native == std::endian::little, "primlabel I/O assumes little-endian");
static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be three packed floats");

// ---------------------------------------------------------------------------------------------
// Messages

template <typename... Parts>
std::string cat(const Parts&... parts) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  (out << ... << parts);
  return out.str();
}

[[noreturn]] inline void throw_io_error(const std::string& path, const std::string& message) {
  throw IoError(path + ": " + message);
}

inline std::string errno_message(int error) { return std::generic_category().message(error); }

// Quotes a token from a (possibly binary, possibly huge) file for an error message.
inline std::string in_quotes(std::string_view token) {
  constexpr std::size_t kMaxShown = 40;
  std::string out = "'";
  for (std::size_t i = 0; i < token.size() && i < kMaxShown; ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    out += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
  }
  if (token.size() > kMaxShown) out += "...";
  out += "'";
  return out;
}

// ---------------------------------------------------------------------------------------------
// Files

// Reads a whole regular file. O_NONBLOCK keeps a FIFO from hanging the open; non-regular files
// are rejected before any read.
inline std::string read_whole_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw_io_error(path, "cannot open: " + errno_message(errno));
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};

  struct stat info {};
  if (::fstat(fd, &info) != 0) throw_io_error(path, "cannot stat: " + errno_message(errno));
  if (!S_ISREG(info.st_mode)) throw_io_error(path, "not a regular file");

  std::string bytes;
  try {
    bytes.resize(static_cast<std::size_t>(info.st_size));
  } catch (const std::bad_alloc&) {
    throw_io_error(path, cat("file of ", info.st_size, " bytes is too large to read into memory"));
  }
  std::size_t filled = 0;
  while (filled < bytes.size()) {
    const ssize_t got = ::read(fd, bytes.data() + filled, bytes.size() - filled);
    if (got < 0) {
      if (errno == EINTR) continue;
      throw_io_error(path, "read failed: " + errno_message(errno));
    }
    if (got == 0) break;  // file shrank while reading
    filled += static_cast<std::size_t>(got);
  }
  bytes.resize(filled);
  return bytes;
}

// Replaces `path` with `bytes` through the one atomic writer (temp file, fsync, rename, directory
// fsync), reporting failures as IoError like every other I/O error of the formats.
inline void write_file_atomically(const std::string& path, std::string_view bytes) {
  try {
    atomic_write_file(path, bytes);
  } catch (const AtomicWriteError& e) {
    throw IoError(e.what());
  }
}

// Header comments (cloud_io.hpp: HeaderComments) as "<marker><line>\n" each; a line break in one
// would end the comment and corrupt the header, so it is refused before anything is written.
inline void append_comment_lines(std::string& out, std::string_view marker,
                                 const std::vector<std::string>& comments) {
  for (const std::string& line : comments) {
    if (line.find_first_of("\r\n") != std::string::npos)
      throw std::invalid_argument("header comment '" + line.substr(0, 40) + "' must be one line");
    out.append(marker).append(line) += '\n';
  }
}

// ---------------------------------------------------------------------------------------------
// Text

inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

// Splits a line on whitespace into `tokens` (reused to avoid reallocating per line).
inline void split_whitespace(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
}

// Strict whole-token parsers: no trailing garbage, no overflow. A leading '+' is accepted.
template <typename Int>
bool parse_integer(std::string_view token, Int& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size();
}

template <typename Float>
bool parse_floating(std::string_view token, Float& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size();
}

// Shortest text that parses back to exactly `value`; every NaN is written as "nan" (PCL's form).
template <typename Float>
void append_floating(std::string& out, Float value) {
  if (std::isnan(value)) {
    out += "nan";
    return;
  }
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

template <typename Int>
void append_integer(std::string& out, Int value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

// Overflow-checked a * b for sizes derived from untrusted headers.
inline bool multiply_fits(std::uint64_t a, std::uint64_t b, std::uint64_t& product) {
  return !__builtin_mul_overflow(a, b, &product);
}

// ---------------------------------------------------------------------------------------------
// Typed binary columns

enum class ScalarKind : std::uint8_t { kFloat, kSigned, kUnsigned };

// A scalar encoding: float (size 4 or 8), signed or unsigned integer (size 1, 2, 4 or 8).
struct ScalarType {
  ScalarKind kind = ScalarKind::kFloat;
  int size = 4;

  bool valid() const {
    if (kind == ScalarKind::kFloat) return size == 4 || size == 8;
    return size == 1 || size == 2 || size == 4 || size == 8;
  }
  bool is_integer() const { return kind != ScalarKind::kFloat; }
};

// Calls visitor(std::type_identity<T>{}) with the C++ type of a valid ScalarType, so the per-value
// loops are compiled once per type instead of switching on every value.
template <typename Visitor>
decltype(auto) visit_scalar_type(ScalarType type, Visitor&& visitor) {
  switch (type.kind) {
    case ScalarKind::kFloat:
      if (type.size == 8) return visitor(std::type_identity<double>{});
      return visitor(std::type_identity<float>{});
    case ScalarKind::kSigned:
      switch (type.size) {
        case 1:
          return visitor(std::type_identity<std::int8_t>{});
        case 2:
          return visitor(std::type_identity<std::int16_t>{});
        case 4:
          return visitor(std::type_identity<std::int32_t>{});
        default:
          return visitor(std::type_identity<std::int64_t>{});
      }
    case ScalarKind::kUnsigned:
    default:
      switch (type.size) {
        case 1:
          return visitor(std::type_identity<std::uint8_t>{});
        case 2:
          return visitor(std::type_identity<std::uint16_t>{});
        case 4:
          return visitor(std::type_identity<std::uint32_t>{});
        default:
          return visitor(std::type_identity<std::uint64_t>{});
      }
  }
}

template <typename T>
T load_scalar(const unsigned char* bytes) {
  T value;
  std::memcpy(&value, bytes, sizeof value);
  return value;
}

inline float to_float(float value) { return value; }
// Out-of-range double -> float conversion is undefined behaviour, so saturate to infinity.
inline float to_float(double value) {
  constexpr double kMax = std::numeric_limits<float>::max();
  if (value > kMax) return std::numeric_limits<float>::infinity();
  if (value < -kMax) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(value);
}
template <typename Int>
requires std::is_integral_v<Int>
float to_float(Int value) { return static_cast<float>(value); }

// One field's values inside a byte buffer: element e of point i starts at
// base + i * point_stride + e * type.size. Covers both point-major records (stride = record size)
// and field-major planes (stride = bytes of one point's field).
struct Column {
  const unsigned char* base = nullptr;
  std::size_t point_stride = 0;
  ScalarType type;
};

// Calls sink(i, value) with element `element` of each of `points` points converted to float.
template <typename Sink>
void for_each_float(const Column& column, std::size_t points, std::size_t element, Sink&& sink) {
  if (points == 0) return;  // base may be null for an empty cloud
  visit_scalar_type(column.type, [&](auto tag) {
    using T = typename decltype(tag)::type;
    const unsigned char* in = column.base + element * sizeof(T);
    for (std::size_t i = 0; i < points; ++i, in += column.point_stride)
      sink(i, to_float(load_scalar<T>(in)));
  });
}

// Address `offset` bytes into a buffer that is null when empty (null + n is undefined).
inline const unsigned char* advance(const unsigned char* base, std::size_t offset) {
  return base ? base + offset : nullptr;
}

// Labels are unsigned 32-bit; anything else (negative, fractional, NaN, too large) is an error
// rather than a silent wrap-around.
inline void decode_labels(const std::string& path, const std::string& field_name,
                          const Column& column, std::size_t points, std::uint32_t* out) {
  if (points == 0) return;
  visit_scalar_type(column.type, [&](auto tag) {
    using T = typename decltype(tag)::type;
    const unsigned char* in = column.base;
    for (std::size_t i = 0; i < points; ++i, in += column.point_stride) {
      const T value = load_scalar<T>(in);
      bool representable;
      if constexpr (std::is_floating_point_v<T>) {
        representable = value >= 0 && value <= 4294967295.0 && std::trunc(value) == value;
      } else if constexpr (std::is_signed_v<T>) {
        representable = value >= 0 && static_cast<std::uint64_t>(value) <= 0xffffffffu;
      } else {
        representable = static_cast<std::uint64_t>(value) <= 0xffffffffu;
      }
      if (!representable) {
        throw_io_error(path, cat("field ", in_quotes(field_name), " of point ", i, ": value ",
                                 +value, " is not a label (an integer in 0..4294967295)"));
      }
      out[i] = static_cast<std::uint32_t>(value);
    }
  });
}

// Copies 4-byte values bit for bit (PCD rgb/rgba are packed colours, even when typed F).
inline void decode_bits32(const Column& column, std::size_t points, std::uint32_t* out) {
  if (points == 0) return;
  const unsigned char* in = column.base;
  for (std::size_t i = 0; i < points; ++i, in += column.point_stride)
    out[i] = load_scalar<std::uint32_t>(in);
}

// ---------------------------------------------------------------------------------------------
// Writing

// Checks that every attribute of `cloud` is either absent or has one entry per point and returns
// the (width, height) to write: an organised cloud must have width * height == size(); anything
// else is written as one unorganised row.
struct Shape {
  std::uint32_t width = 0;
  std::uint32_t height = 1;
};

inline Shape validate_cloud_for_writing(const std::string& path, const PointCloud& cloud) {
  const std::size_t n = cloud.size();
  if (n > std::numeric_limits<std::uint32_t>::max())
    throw_io_error(path, cat("cannot write ", n, " points (at most 4294967295)"));
  auto check_size = [&](const char* what, std::size_t entries) {
    if (entries != 0 && entries != n)
      throw_io_error(path,
                     cat("cannot write: ", what, " has ", entries, " entries for ", n, " points"));
  };
  check_size("normals", cloud.normals.size());
  check_size("curvature", cloud.curvature.size());
  check_size("labels", cloud.labels.size());
  check_size("rgba", cloud.rgba.size());
  for (const FloatField& field : cloud.fields) {
    bool name_ok = !field.name.empty() && field.name != "_";
    for (const char c : field.name)
      name_ok =
          name_ok && static_cast<unsigned char>(c) > 0x20 && static_cast<unsigned char>(c) < 0x7f;
    if (!name_ok)
      throw_io_error(path, cat("cannot write: invalid field name ", in_quotes(field.name)));
    if (field.count < 1)
      throw_io_error(
          path, cat("cannot write: field ", in_quotes(field.name), " has count ", field.count));
    if (field.values.size() != n * static_cast<std::size_t>(field.count))
      throw_io_error(
          path, cat("cannot write: field ", in_quotes(field.name), " has ", field.values.size(),
                    " values, expected ", n, " points x ", field.count));
  }
  if (cloud.height > 1) {
    if (static_cast<std::uint64_t>(cloud.width) * cloud.height != n)
      throw_io_error(path, cat("cannot write: organised cloud is ", cloud.width, " x ",
                               cloud.height, " but has ", n, " points"));
    return {cloud.width, cloud.height};
  }
  return {static_cast<std::uint32_t>(n), 1};
}

// Rejects duplicate names among the fields/properties about to be written (e.g. a FloatField
// called "x"), which would make the file ambiguous.
inline void check_unique_names(const std::string& path, const std::vector<std::string>& names) {
  std::unordered_set<std::string_view> seen;
  for (const std::string& name : names)
    if (!seen.insert(name).second)
      throw_io_error(path, cat("cannot write: two fields named ", in_quotes(name)));
}

}  // namespace primlabel::io_detail
