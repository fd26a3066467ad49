// PCD v0.7 reading and writing (DATA ascii, binary, binary_compressed), compatible with PCL.
//
// Reading parses the header, locates every field's values as a typed Column (inside point-major
// records for ascii/binary, inside field-major planes for binary_compressed) and converts each
// column in one typed loop. Every size taken from the header is checked against the bytes that
// are really in the file before anything proportional to it is allocated.

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io_util.hpp"
#include "lzf_decode.hpp"
#include "lzf_encode.hpp"
#include "primlabel/geometry/cloud_io.hpp"

namespace primlabel::io_detail {
namespace {

constexpr std::string_view kPaddingName = "_";
// An LZF back-reference of at most 3 bytes expands to at most 264 bytes, so no valid stream
// decompresses to more than 88 times its size; a larger claim is corrupt and is not allocated.
constexpr std::uint64_t kMaxLzfExpansion = 88;

struct PcdField {
  std::string name;
  ScalarType type;
  std::uint32_t count = 1;

  std::uint64_t bytes() const { return std::uint64_t{count} * static_cast<unsigned>(type.size); }
  bool is_padding() const { return name == kPaddingName; }
};

struct PcdHeader {
  std::vector<PcdField> fields;
  std::uint32_t width = 0;
  std::uint32_t height = 1;
  std::uint64_t points = 0;
  Viewpoint viewpoint;
  PcdEncoding encoding = PcdEncoding::kAscii;
  std::size_t data_offset = 0;              // first byte after the DATA line
  int data_line = 0;                        // line number of the DATA line
  std::uint64_t record_bytes = 0;           // one point in ascii/binary layout (with padding)
  std::uint64_t unpadded_record_bytes = 0;  // one point in binary_compressed layout (no "_")
  std::uint64_t values_per_point = 0;       // ascii tokens per point (padding included)
};

// "fpfh", 3 -> "fpfh_3": the scalar columns a multi-value field is also written as.
std::string scalar_column_name(const std::string& field, std::uint32_t element) {
  return field + "_" + std::to_string(element);
}

// True for a COUNT 1 field name_e beside a field `name` with more than e values: the copy our
// writer adds for readers that take one value per field, read back as part of `name`.
bool is_scalar_copy(const PcdHeader& header, const PcdField& field) {
  if (field.count != 1) return false;
  const std::size_t underscore = field.name.rfind('_');
  if (underscore == std::string::npos || underscore + 1 == field.name.size()) return false;
  std::uint32_t element = 0;
  const char* first = field.name.data() + underscore + 1;
  const char* last = field.name.data() + field.name.size();
  const auto [end, error] = std::from_chars(first, last, element);
  if (error != std::errc() || end != last) return false;
  const std::string base = field.name.substr(0, underscore);
  for (const PcdField& other : header.fields)
    if (other.name == base && other.count > element) return true;
  return false;
}

// The entries of one header line, remembered with its line number for error messages.
struct HeaderLine {
  std::vector<std::string> values;
  int line = 0;
};

struct HeaderNumber {
  std::uint64_t value = 0;
  int line = 0;
};

// Attributes with a dedicated PointCloud member; each must be a single value per point.
constexpr std::array<std::string_view, 10> kSingleValueFields = {
    "x", "y", "z", "normal_x", "normal_y", "normal_z", "curvature", "label", "rgb", "rgba"};

class PcdHeaderParser {
 public:
  PcdHeaderParser(const std::string& path, std::string_view file) : path_(path), file_(file) {}

  PcdHeader parse() {
    scan_lines();
    build_fields();
    resolve_shape();
    return header_;
  }

 private:
  [[noreturn]] void fail_at(int line, const std::string& message) const {
    throw_io_error(path_, cat("header line ", line, ": ", message));
  }
  [[noreturn]] void fail(const std::string& message) const {
    throw_io_error(path_, "header: " + message);
  }

  // Reads header lines up to and including DATA, remembering each keyword's entries.
  void scan_lines() {
    std::vector<std::string_view> tokens;
    std::size_t pos = 0;
    int line_number = 0;
    while (pos < file_.size()) {
      const std::size_t end_of_line = std::min(file_.find('\n', pos), file_.size());
      const std::string_view line = file_.substr(pos, end_of_line - pos);
      pos = std::min(end_of_line + 1, file_.size());
      ++line_number;
      split_whitespace(line, tokens);
      if (tokens.empty() || tokens[0].front() == '#') continue;

      const std::string_view keyword = tokens[0];
      const std::vector<std::string_view> values(tokens.begin() + 1, tokens.end());
      if (keyword == "VERSION") {
        check_version(line_number, values);
      } else if (keyword == "FIELDS" || keyword == "COLUMNS") {
        remember(fields_, "FIELDS", line_number, values);
        if (values.empty()) fail_at(line_number, "FIELDS lists no fields");
      } else if (keyword == "SIZE") {
        remember(sizes_, "SIZE", line_number, values);
      } else if (keyword == "TYPE") {
        remember(types_, "TYPE", line_number, values);
      } else if (keyword == "COUNT") {
        remember(counts_, "COUNT", line_number, values);
      } else if (keyword == "WIDTH") {
        width_ = parse_dimension("WIDTH", line_number, values, width_);
      } else if (keyword == "HEIGHT") {
        height_ = parse_dimension("HEIGHT", line_number, values, height_);
      } else if (keyword == "POINTS") {
        points_ = parse_dimension("POINTS", line_number, values, points_);
      } else if (keyword == "VIEWPOINT") {
        parse_viewpoint(line_number, values);
      } else if (keyword == "DATA") {
        parse_data_kind(line_number, values);
        header_.data_offset = pos;
        header_.data_line = line_number;
        return;
      } else if (looks_numeric(keyword)) {
        fail_at(line_number, cat("data value ", in_quotes(keyword),
                                 " before any DATA line (missing DATA line?)"));
      } else if (line_number == 1 && keyword == "ply" && values.empty()) {
        // The one mistake worth naming: a PLY given to the PCD reader (a wrong extension).
        fail_at(line_number, "a PLY file, not a PCD file (read it with the PLY reader)");
      } else {
        fail_at(line_number, cat("unknown header keyword ", in_quotes(keyword)));
      }
    }
    if (file_.empty()) throw_io_error(path_, "empty file, not a PCD file");
    fail("missing DATA line (the header runs to the end of the file)");
  }

  static bool looks_numeric(std::string_view token) {
    const char c = token.front();
    return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
  }

  void check_version(int line, const std::vector<std::string_view>& values) {
    static constexpr std::array<std::string_view, 6> kAccepted = {"0.7", ".7",  "0.6",
                                                                  ".6",  "0.5", ".5"};
    if (values.size() != 1) fail_at(line, "VERSION needs exactly one value");
    if (std::find(kAccepted.begin(), kAccepted.end(), values[0]) == kAccepted.end())
      fail_at(line, cat("unsupported VERSION ", in_quotes(values[0]), " (0.5 to 0.7 are read)"));
  }

  void remember(std::optional<HeaderLine>& slot, const char* keyword, int line,
                const std::vector<std::string_view>& values) {
    if (slot) fail_at(line, cat("duplicate ", keyword, " line (first on line ", slot->line, ")"));
    slot = HeaderLine{{values.begin(), values.end()}, line};
  }

  std::optional<HeaderNumber> parse_dimension(const char* keyword, int line,
                                              const std::vector<std::string_view>& values,
                                              const std::optional<HeaderNumber>& previous) {
    if (previous)
      fail_at(line, cat("duplicate ", keyword, " line (first on line ", previous->line, ")"));
    if (values.size() != 1) fail_at(line, cat(keyword, " needs exactly one value"));
    std::uint64_t value = 0;
    if (!parse_integer(values[0], value))
      fail_at(line, cat(keyword, " must be a non-negative integer, got ", in_quotes(values[0])));
    return HeaderNumber{value, line};
  }

  void parse_viewpoint(int line, const std::vector<std::string_view>& values) {
    if (values.size() != 7)
      fail_at(line, cat("VIEWPOINT needs 7 values (tx ty tz qw qx qy qz), got ", values.size()));
    std::array<float, 7> numbers{};
    for (std::size_t i = 0; i < 7; ++i)
      if (!parse_floating(values[i], numbers[i]))
        fail_at(line, cat("VIEWPOINT value ", in_quotes(values[i]), " is not a number"));
    header_.viewpoint.origin = Vec3f(numbers[0], numbers[1], numbers[2]);
    header_.viewpoint.orientation =
        Eigen::Quaternionf(numbers[3], numbers[4], numbers[5], numbers[6]);
  }

  void parse_data_kind(int line, const std::vector<std::string_view>& values) {
    if (values.size() != 1) fail_at(line, "DATA needs exactly one value");
    if (values[0] == "ascii") {
      header_.encoding = PcdEncoding::kAscii;
    } else if (values[0] == "binary") {
      header_.encoding = PcdEncoding::kBinary;
    } else if (values[0] == "binary_compressed") {
      header_.encoding = PcdEncoding::kBinaryCompressed;
    } else {
      fail_at(line, cat("unknown DATA kind ", in_quotes(values[0]),
                        " (expected ascii, binary or binary_compressed)"));
    }
  }

  // Combines FIELDS/SIZE/TYPE/COUNT into typed fields. SIZE, TYPE and COUNT may be missing
  // (older PCD versions); they then default to 4, F and 1.
  void build_fields() {
    if (!fields_) fail("missing FIELDS line");
    const std::size_t n = fields_->values.size();
    auto check_entries = [&](const std::optional<HeaderLine>& entries, const char* keyword) {
      if (entries && entries->values.size() != n)
        fail_at(entries->line,
                cat(keyword, " has ", entries->values.size(), " entries but FIELDS has ", n));
    };
    check_entries(sizes_, "SIZE");
    check_entries(types_, "TYPE");
    check_entries(counts_, "COUNT");

    header_.fields.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      PcdField& field = header_.fields[i];
      field.name = fields_->values[i];
      int size = 4;
      if (sizes_) {
        const std::string& text = sizes_->values[i];
        if (!parse_integer(text, size) || (size != 1 && size != 2 && size != 4 && size != 8))
          fail_at(sizes_->line, cat("SIZE of field ", in_quotes(field.name), " is ",
                                    in_quotes(text), ", expected 1, 2, 4 or 8"));
      }
      ScalarKind kind = ScalarKind::kFloat;
      if (types_) {
        const std::string& text = types_->values[i];
        if (text == "F") {
          kind = ScalarKind::kFloat;
        } else if (text == "I") {
          kind = ScalarKind::kSigned;
        } else if (text == "U") {
          kind = ScalarKind::kUnsigned;
        } else {
          fail_at(types_->line, cat("TYPE of field ", in_quotes(field.name), " is ",
                                    in_quotes(text), ", expected F, I or U"));
        }
      }
      field.type = ScalarType{kind, size};
      if (!field.type.valid())
        fail_at(types_ ? types_->line : sizes_->line,
                cat("field ", in_quotes(field.name), " has TYPE F with SIZE ", size,
                    " (F needs SIZE 4 or 8)"));
      if (counts_) {
        const std::string& text = counts_->values[i];
        if (!parse_integer(text, field.count) || field.count == 0)
          fail_at(counts_->line, cat("COUNT of field ", in_quotes(field.name), " is ",
                                     in_quotes(text), ", expected a positive integer"));
      }
    }
    check_field_names();

    for (const PcdField& field : header_.fields) {
      // Sums of at most 2^32 fields of at most 2^35 bytes each cannot overflow 64 bits.
      header_.record_bytes += field.bytes();
      header_.values_per_point += field.count;
      if (!field.is_padding()) header_.unpadded_record_bytes += field.bytes();
    }
  }

  void check_field_names() {
    const int line = fields_->line;
    for (std::size_t i = 0; i < header_.fields.size(); ++i) {
      const PcdField& field = header_.fields[i];
      if (field.is_padding()) continue;
      for (std::size_t j = 0; j < i; ++j)
        if (header_.fields[j].name == field.name)
          fail_at(line, cat("field ", in_quotes(field.name), " is listed twice"));
      const bool single = std::find(kSingleValueFields.begin(), kSingleValueFields.end(),
                                    field.name) != kSingleValueFields.end();
      if (single && field.count != 1)
        fail_at(counts_ ? counts_->line : line,
                cat("field ", in_quotes(field.name), " must have COUNT 1, got ", field.count));
      if ((field.name == "rgb" || field.name == "rgba") && field.type.size != 4)
        fail_at(sizes_ ? sizes_->line : line,
                cat("field ", in_quotes(field.name), " is a packed colour and needs SIZE 4, got ",
                    field.type.size));
    }
    auto has = [&](std::string_view name) {
      return std::any_of(header_.fields.begin(), header_.fields.end(),
                         [&](const PcdField& f) { return f.name == name; });
    };
    for (const char* axis : {"x", "y", "z"})
      if (!has(axis)) fail_at(line, cat("missing field '", axis, "' (x, y and z are required)"));
    if (has("rgb") && has("rgba")) fail_at(line, "both 'rgb' and 'rgba' are present");
  }

  // WIDTH x HEIGHT must equal POINTS; older files may omit WIDTH/HEIGHT (one row) or POINTS.
  void resolve_shape() {
    if (!points_ && !width_) fail("missing POINTS and WIDTH lines");
    if (width_ && width_->value > 0xffffffffu)
      fail_at(width_->line, cat("WIDTH ", width_->value, " exceeds 4294967295"));
    if (height_ && height_->value > 0xffffffffu)
      fail_at(height_->line, cat("HEIGHT ", height_->value, " exceeds 4294967295"));
    const std::uint64_t height = height_ ? height_->value : 1;
    if (!width_) {
      if (height != 1) fail_at(height_->line, "HEIGHT given without WIDTH");
      width_ = HeaderNumber{points_->value, points_->line};
      if (width_->value > 0xffffffffu)
        fail_at(points_->line, cat("POINTS ", points_->value, " exceeds 4294967295 for one row"));
    }
    const std::uint64_t product = width_->value * height;  // both < 2^32: no overflow
    if (!points_) points_ = HeaderNumber{product, width_->line};
    if (product != points_->value)
      fail_at(points_->line, cat("WIDTH ", width_->value, " x HEIGHT ", height, " = ", product,
                                 " does not match POINTS ", points_->value));
    header_.width = static_cast<std::uint32_t>(width_->value);
    header_.height = static_cast<std::uint32_t>(height);
    header_.points = points_->value;
    // An empty cloud may say WIDTH 3 HEIGHT 0 (or 0 x 5); PointCloud keeps width x height equal
    // to its size, so any zero-area shape becomes one empty row.
    if (header_.points == 0) {
      header_.width = 0;
      header_.height = 1;
    }
  }

  const std::string& path_;
  std::string_view file_;
  PcdHeader header_;
  std::optional<HeaderLine> fields_, sizes_, types_, counts_;
  std::optional<HeaderNumber> width_, height_, points_;
};

// Parses one ascii token into the binary representation of `type` at `out`.
bool parse_scalar_into(ScalarType type, std::string_view token, unsigned char* out) {
  return visit_scalar_type(type, [&](auto tag) {
    using T = typename decltype(tag)::type;
    T value{};
    bool ok;
    if constexpr (std::is_floating_point_v<T>) {
      ok = parse_floating(token, value);
    } else {
      ok = parse_integer(token, value);
    }
    if (ok) std::memcpy(out, &value, sizeof value);
    return ok;
  });
}

std::string type_name(ScalarType type) {
  const char letter = type.kind == ScalarKind::kFloat    ? 'F'
                      : type.kind == ScalarKind::kSigned ? 'I'
                                                         : 'U';
  return cat(letter, ' ', type.size);
}

// Converts ascii lines into point-major binary records (the DATA binary layout) so that all
// encodings share one decoding path. Grows with the data actually present, never with POINTS.
std::vector<unsigned char> parse_ascii_records(const std::string& path, const PcdHeader& header,
                                               std::string_view file) {
  const std::string_view data = file.substr(header.data_offset);
  std::vector<unsigned char> records;
  // Every value takes at least two bytes (digit + separator), which bounds the reservation.
  if (header.values_per_point <= data.size()) {
    const std::uint64_t likely_points =
        std::min<std::uint64_t>(header.points, data.size() / (2 * header.values_per_point) + 1);
    records.reserve(likely_points * header.record_bytes);
  }

  std::vector<std::string_view> tokens;
  std::uint64_t parsed_points = 0;
  int line_number = header.data_line;
  std::size_t pos = 0;
  while (pos < data.size()) {
    const std::size_t end_of_line = std::min(data.find('\n', pos), data.size());
    const std::string_view line = data.substr(pos, end_of_line - pos);
    pos = std::min(end_of_line + 1, data.size());
    ++line_number;
    split_whitespace(line, tokens);
    if (tokens.empty()) continue;
    auto fail = [&](const std::string& message) {
      throw_io_error(path, cat("line ", line_number, ": ", message));
    };
    if (parsed_points == header.points)
      fail(cat("more data lines than POINTS (", header.points, ")"));
    if (tokens.size() != header.values_per_point)
      fail(cat("expected ", header.values_per_point, " values for point ", parsed_points,
               ", found ", tokens.size()));

    const std::size_t record_start = records.size();
    records.resize(record_start + header.record_bytes);
    unsigned char* out = records.data() + record_start;
    std::size_t token_index = 0;
    for (const PcdField& field : header.fields) {
      for (std::uint32_t e = 0; e < field.count; ++e, ++token_index, out += field.type.size) {
        if (field.is_padding()) continue;
        const std::string_view token = tokens[token_index];
        if (!parse_scalar_into(field.type, token, out))
          fail(cat("value ", in_quotes(token), " of field ", in_quotes(field.name),
                   " is not a valid ", type_name(field.type), " number"));
      }
    }
    ++parsed_points;
  }
  if (parsed_points != header.points)
    throw_io_error(path, cat("ascii data ends after ", parsed_points, " points, POINTS declares ",
                             header.points));
  return records;
}

// Columns of point-major records (ascii after conversion, and DATA binary).
std::vector<Column> record_columns(const PcdHeader& header, const unsigned char* records) {
  std::vector<Column> columns;
  std::size_t offset = 0;
  for (const PcdField& field : header.fields) {
    columns.push_back(Column{advance(records, offset), header.record_bytes, field.type});
    offset += field.bytes();
  }
  return columns;
}

void check_binary_size(const std::string& path, const PcdHeader& header, std::uint64_t available) {
  std::uint64_t needed = 0;
  if (!multiply_fits(header.points, header.record_bytes, needed) || needed > available)
    throw_io_error(path, cat("truncated binary data: expected ",
                             needed ? cat(needed) : cat(header.points, " x ", header.record_bytes),
                             " bytes for ", header.points, " points, found ", available));
}

// Decompresses DATA binary_compressed: uint32 compressed size, uint32 uncompressed size, then LZF
// data holding, field after field, every point's values of that field ("_" fields are absent).
std::unique_ptr<unsigned char[]> decompress_planes(const std::string& path, const PcdHeader& header,
                                                   std::string_view data) {
  if (data.size() < 8) {
    if (header.points == 0) return nullptr;
    throw_io_error(path, cat("truncated binary_compressed data: expected an 8-byte size header, "
                             "found ",
                             data.size(), " bytes"));
  }
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  const std::uint32_t compressed_size = load_scalar<std::uint32_t>(bytes);
  const std::uint32_t uncompressed_size = load_scalar<std::uint32_t>(bytes + 4);
  std::uint64_t expected = 0;
  if (!multiply_fits(header.points, header.unpadded_record_bytes, expected) ||
      expected != uncompressed_size)
    throw_io_error(
        path, cat("binary_compressed header says ", uncompressed_size, " uncompressed bytes, but ",
                  header.points, " points x ", header.unpadded_record_bytes, " bytes need ",
                  expected ? cat(expected) : std::string("more than 2^64")));
  const std::uint64_t available = data.size() - 8;
  if (compressed_size > available)
    throw_io_error(path, cat("compressed size ", compressed_size, " is larger than the ", available,
                             " bytes remaining in the file"));
  if (uncompressed_size == 0) return nullptr;
  if (uncompressed_size > std::uint64_t{compressed_size} * kMaxLzfExpansion)
    throw_io_error(path, cat("LZF data of ", compressed_size, " bytes cannot expand to ",
                             uncompressed_size, " bytes (corrupt size header)"));

  auto planes = std::make_unique_for_overwrite<unsigned char[]>(uncompressed_size);
  const LzfDecoded decoded =
      lzf_decode(bytes + 8, compressed_size, planes.get(), uncompressed_size);
  if (decoded.status != LzfStatus::kOk || decoded.produced != uncompressed_size) {
    const std::string reason =
        decoded.status == LzfStatus::kOutputOverflow ? "output exceeds the declared size"
        : decoded.status == LzfStatus::kInvalid      ? "invalid compressed stream"
                                                     : cat("produced ", decoded.produced, " bytes");
    throw_io_error(path, cat("LZF decompression failed: ", reason, " (expected ", uncompressed_size,
                             " bytes)"));
  }
  return planes;
}

std::vector<Column> plane_columns(const PcdHeader& header, const unsigned char* planes) {
  std::vector<Column> columns;
  std::size_t offset = 0;
  for (const PcdField& field : header.fields) {
    if (field.is_padding()) {
      columns.push_back(Column{nullptr, 0, field.type});
      continue;
    }
    columns.push_back(Column{advance(planes, offset), field.bytes(), field.type});
    offset += field.bytes() * header.points;
  }
  return columns;
}

// Maps decoded columns to PointCloud members; every unrecognised field becomes a FloatField.
PointCloud assemble_cloud(const std::string& path, const PcdHeader& header,
                          const std::vector<Column>& columns) {
  const std::size_t n = header.points;
  auto index_of = [&](std::string_view name) -> int {
    for (std::size_t i = 0; i < header.fields.size(); ++i)
      if (header.fields[i].name == name) return static_cast<int>(i);
    return -1;
  };

  PointCloud cloud;
  cloud.width = header.width;
  cloud.height = header.height;
  cloud.viewpoint = header.viewpoint;
  std::vector<bool> consumed(header.fields.size(), false);

  cloud.xyz.resize(n);
  const std::array<int, 3> xyz = {index_of("x"), index_of("y"), index_of("z")};
  for (int axis = 0; axis < 3; ++axis) {
    for_each_float(columns[xyz[axis]], n, 0,
                   [&](std::size_t i, float v) { cloud.xyz[i][axis] = v; });
    consumed[xyz[axis]] = true;
  }

  const std::array<int, 3> normal = {index_of("normal_x"), index_of("normal_y"),
                                     index_of("normal_z")};
  if (normal[0] >= 0 && normal[1] >= 0 && normal[2] >= 0) {
    cloud.normals.resize(n);
    for (int axis = 0; axis < 3; ++axis) {
      for_each_float(columns[normal[axis]], n, 0,
                     [&](std::size_t i, float v) { cloud.normals[i][axis] = v; });
      consumed[normal[axis]] = true;
    }
  }

  if (const int curvature = index_of("curvature"); curvature >= 0) {
    cloud.curvature.resize(n);
    for_each_float(columns[curvature], n, 0,
                   [&](std::size_t i, float v) { cloud.curvature[i] = v; });
    consumed[curvature] = true;
  }

  if (const int label = index_of("label"); label >= 0) {
    cloud.labels.resize(n);
    decode_labels(path, "label", columns[label], n, cloud.labels.data());
    consumed[label] = true;
  }

  const int colour = index_of("rgba") >= 0 ? index_of("rgba") : index_of("rgb");
  if (colour >= 0) {
    cloud.rgba.resize(n);
    decode_bits32(columns[colour], n, cloud.rgba.data());
    consumed[colour] = true;
  }

  for (std::size_t f = 0; f < header.fields.size(); ++f) {
    const PcdField& field = header.fields[f];
    if (consumed[f] || field.is_padding() || is_scalar_copy(header, field)) continue;
    FloatField out{field.name, static_cast<int>(field.count), {}};
    out.values.resize(n * field.count);
    for (std::size_t e = 0; e < field.count; ++e)
      for_each_float(columns[f], n, e,
                     [&](std::size_t i, float v) { out.values[i * field.count + e] = v; });
    cloud.fields.push_back(std::move(out));
  }
  return cloud;
}

PointCloud read_pcd_file(const std::string& path) {
  const std::string file = read_whole_file(path);
  const PcdHeader header = PcdHeaderParser(path, file).parse();
  const std::string_view data = std::string_view(file).substr(header.data_offset);

  switch (header.encoding) {
    case PcdEncoding::kAscii: {
      const std::vector<unsigned char> records = parse_ascii_records(path, header, file);
      return assemble_cloud(path, header, record_columns(header, records.data()));
    }
    case PcdEncoding::kBinary:
      check_binary_size(path, header, data.size());
      return assemble_cloud(
          path, header,
          record_columns(header, reinterpret_cast<const unsigned char*>(data.data())));
    case PcdEncoding::kBinaryCompressed:
    default: {
      const auto planes = decompress_planes(path, header, data);
      return assemble_cloud(path, header, plane_columns(header, planes.get()));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Writing

// One output field: every value is 4 bytes; element e of point i is at
// base + offset + i * point_stride + 4 * e (base is null for an empty cloud, so the offset is
// only applied once a point is addressed).
struct OutputField {
  std::string name;
  char type = 'F';
  std::uint32_t count = 1;
  const unsigned char* base = nullptr;
  std::size_t offset = 0;
  std::size_t point_stride = 0;

  const unsigned char* point(std::size_t i) const { return base + offset + i * point_stride; }
};

std::vector<OutputField> output_fields(const PointCloud& cloud) {
  std::vector<OutputField> out;
  auto bytes = [](const auto* pointer) { return reinterpret_cast<const unsigned char*>(pointer); };
  const auto* xyz = bytes(cloud.xyz.data());
  out.push_back({"x", 'F', 1, xyz, 0, sizeof(Vec3f)});
  out.push_back({"y", 'F', 1, xyz, 4, sizeof(Vec3f)});
  out.push_back({"z", 'F', 1, xyz, 8, sizeof(Vec3f)});
  if (cloud.has_normals()) {
    const auto* normals = bytes(cloud.normals.data());
    out.push_back({"normal_x", 'F', 1, normals, 0, sizeof(Vec3f)});
    out.push_back({"normal_y", 'F', 1, normals, 4, sizeof(Vec3f)});
    out.push_back({"normal_z", 'F', 1, normals, 8, sizeof(Vec3f)});
  }
  if (cloud.has_curvature())
    out.push_back({"curvature", 'F', 1, bytes(cloud.curvature.data()), 0, 4});
  if (cloud.has_labels()) out.push_back({"label", 'U', 1, bytes(cloud.labels.data()), 0, 4});
  if (cloud.has_rgba()) out.push_back({"rgba", 'U', 1, bytes(cloud.rgba.data()), 0, 4});
  for (const FloatField& field : cloud.fields) {
    const auto count = static_cast<std::uint32_t>(field.count);
    out.push_back({field.name, 'F', count, bytes(field.values.data()), 0, 4 * std::size_t{count}});
  }
  // PCL reads a multi-value field (fpfh, COUNT 33) as one; Open3D keeps only its first value. So
  // each also goes out as scalar columns name_0 .. name_k (views of the same values), which our
  // reader folds back; skipped when the cloud already has a field of such a name.
  for (const FloatField& field : cloud.fields) {
    if (field.count < 2) continue;
    const auto count = static_cast<std::uint32_t>(field.count);
    bool taken = false;
    for (std::uint32_t e = 0; e < count && !taken; ++e)
      taken = cloud.find_field(scalar_column_name(field.name, e)) != nullptr;
    if (taken) continue;
    for (std::uint32_t e = 0; e < count; ++e)
      out.push_back({scalar_column_name(field.name, e), 'F', 1, bytes(field.values.data()), 4 * e,
                     4 * std::size_t{count}});
  }
  return out;
}

std::string pcd_header(const PointCloud& cloud, Shape shape, const std::vector<OutputField>& fields,
                       PcdEncoding encoding, const HeaderComments& comments) {
  std::string names, sizes, types, counts;
  for (const OutputField& field : fields) {
    names += ' ' + field.name;
    sizes += " 4";
    types += ' ';
    types += field.type;
    counts += ' ';
    append_integer(counts, field.count);
  }
  std::string header = "# .PCD v0.7 - Point Cloud Data file format\n";
  append_comment_lines(header, "# ", comments);
  header += "VERSION 0.7\n";
  header += "FIELDS" + names + "\nSIZE" + sizes + "\nTYPE" + types + "\nCOUNT" + counts;
  header += cat("\nWIDTH ", shape.width, "\nHEIGHT ", shape.height, "\nVIEWPOINT");
  const Viewpoint& view = cloud.viewpoint;
  for (float value : {view.origin.x(), view.origin.y(), view.origin.z(), view.orientation.w(),
                      view.orientation.x(), view.orientation.y(), view.orientation.z()}) {
    header += ' ';
    append_floating(header, value);
  }
  header += cat("\nPOINTS ", cloud.size(), "\nDATA ");
  header += encoding == PcdEncoding::kAscii    ? "ascii\n"
            : encoding == PcdEncoding::kBinary ? "binary\n"
                                               : "binary_compressed\n";
  return header;
}

void append_ascii_body(std::string& out, std::size_t points,
                       const std::vector<OutputField>& fields) {
  for (std::size_t i = 0; i < points; ++i) {
    bool first = true;
    for (const OutputField& field : fields) {
      const unsigned char* in = field.point(i);
      for (std::uint32_t e = 0; e < field.count; ++e, in += 4) {
        if (!first) out += ' ';
        first = false;
        if (field.type == 'U')
          append_integer(out, load_scalar<std::uint32_t>(in));
        else
          append_floating(out, load_scalar<float>(in));
      }
    }
    out += '\n';
  }
}

std::uint64_t record_bytes_of(const std::vector<OutputField>& fields) {
  std::uint64_t bytes = 0;
  for (const OutputField& field : fields) bytes += 4 * std::uint64_t{field.count};
  return bytes;
}

// Copies one value of `bytes` bytes; the common 4-byte case with a constant size, which the
// compiler turns into one load and store instead of a memcpy call per value.
inline void copy_value(unsigned char* out, const unsigned char* in, std::size_t bytes) {
  if (bytes == 4)
    std::memcpy(out, in, 4);
  else
    std::memcpy(out, in, bytes);
}

void append_binary_body(std::string& out, std::size_t points,
                        const std::vector<OutputField>& fields) {
  const std::size_t start = out.size();
  out.resize(start + points * record_bytes_of(fields));
  auto* record = reinterpret_cast<unsigned char*>(out.data() + start);
  for (std::size_t i = 0; i < points; ++i) {
    for (const OutputField& field : fields) {
      const std::size_t bytes = 4 * std::size_t{field.count};
      copy_value(record, field.point(i), bytes);
      record += bytes;
    }
  }
}

// Values of points [first, first + count) of one field, one after another (part of a
// binary_compressed plane).
void gather_values(const OutputField& field, std::size_t first, std::size_t count,
                   unsigned char* out) {
  const std::size_t bytes = 4 * std::size_t{field.count};
  if (count == 0) return;
  if (field.point_stride == bytes) {  // already contiguous: labels, rgba, scalar fields
    std::memcpy(out, field.point(first), count * bytes);
    return;
  }
  const unsigned char* in = field.point(first);
  for (std::size_t i = 0; i < count; ++i, in += field.point_stride, out += bytes)
    copy_value(out, in, bytes);
}

// The planes cut into segments of at most `segment_bytes` (whole values, never across two
// fields) for CloudWriteOptions: a field whose values are contiguous in the cloud is compressed
// where it is, the others (x, y, z, normals) are gathered into a thread's scratch first.
std::vector<LzfSegment> plane_segments(const std::vector<OutputField>& fields, std::size_t points,
                                       std::size_t segment_bytes) {
  std::vector<LzfSegment> segments;
  for (const OutputField& field : fields) {
    const std::size_t value_bytes = 4 * std::size_t{field.count};
    const std::size_t per_segment = std::max<std::size_t>(1, segment_bytes / value_bytes);
    for (std::size_t first = 0; first < points; first += per_segment) {
      const std::size_t count = std::min(per_segment, points - first);
      segments.push_back({count * value_bytes, [&field, first, count](unsigned char* scratch) {
                            if (field.point_stride == 4 * std::size_t{field.count})
                              return field.point(first);
                            gather_values(field, first, count, scratch);
                            return static_cast<const unsigned char*>(scratch);
                          }});
    }
  }
  return segments;
}

// A whole binary_compressed file: the header, uint32 compressed and uncompressed sizes, the LZF
// data of the planes. Built in one buffer that is neither zero-filled nor copied again: the LZF
// data is compressed straight into place after the header.
void write_compressed_file(const std::string& path, const std::string& header, std::size_t points,
                           const std::vector<OutputField>& fields,
                           const CloudWriteOptions& options) {
  const std::uint64_t plane_bytes = points * record_bytes_of(fields);
  const bool segmented = options.lzf_segment_bytes > 0 && plane_bytes > options.lzf_segment_bytes;
  const std::vector<LzfSegment> segments =
      segmented ? plane_segments(fields, points, options.lzf_segment_bytes)
                : std::vector<LzfSegment>{};
  // Both sizes are stored as uint32; leave room for LZF's worst-case expansion.
  const std::uint64_t capacity =
      segmented ? lzf_segments_capacity(segments) : lzf_stream_capacity(plane_bytes);
  if (capacity > 0xffffffffu)
    throw_io_error(path, cat("cannot write binary_compressed: ", plane_bytes,
                             " bytes of point data exceed the format's 32-bit size fields"));

  const std::size_t data_offset = header.size() + 8;
  auto file = std::make_unique_for_overwrite<unsigned char[]>(data_offset + capacity);
  std::memcpy(file.get(), header.data(), header.size());
  std::size_t compressed = 0;
  if (segmented) {
    compressed = lzf_encode_segments(segments, options.threads, file.get() + data_offset);
  } else {
    auto planes = std::make_unique_for_overwrite<unsigned char[]>(plane_bytes);
    unsigned char* plane = planes.get();
    for (const OutputField& field : fields) {
      gather_values(field, 0, points, plane);
      plane += points * 4 * std::size_t{field.count};
    }
    compressed = lzf_encode(planes.get(), plane_bytes, file.get() + data_offset);
  }
  if (plane_bytes > 0 && compressed == 0) throw_io_error(path, "LZF compression failed");
  const auto compressed_size = static_cast<std::uint32_t>(compressed);
  const auto uncompressed_size = static_cast<std::uint32_t>(plane_bytes);
  std::memcpy(file.get() + header.size(), &compressed_size, 4);
  std::memcpy(file.get() + header.size() + 4, &uncompressed_size, 4);
  write_file_atomically(path, std::string_view(reinterpret_cast<const char*>(file.get()),
                                               data_offset + compressed_size));
}

void write_pcd_file(const std::string& path, const PointCloud& cloud, PcdEncoding encoding,
                    const HeaderComments& comments, const CloudWriteOptions& options) {
  const Shape shape = validate_cloud_for_writing(path, cloud);
  const std::vector<OutputField> fields = output_fields(cloud);
  std::vector<std::string> names;
  for (const OutputField& field : fields) names.push_back(field.name);
  check_unique_names(path, names);

  std::string out = pcd_header(cloud, shape, fields, encoding, comments);
  switch (encoding) {
    case PcdEncoding::kAscii:
      append_ascii_body(out, cloud.size(), fields);
      break;
    case PcdEncoding::kBinary:
      append_binary_body(out, cloud.size(), fields);
      break;
    case PcdEncoding::kBinaryCompressed:
      write_compressed_file(path, out, cloud.size(), fields, options);
      return;
  }
  write_file_atomically(path, out);
}

}  // namespace
}  // namespace primlabel::io_detail

namespace primlabel {

PointCloud read_pcd(const std::string& path) { return io_detail::read_pcd_file(path); }

void write_pcd(const std::string& path, const PointCloud& cloud, PcdEncoding encoding,
               const HeaderComments& comments, const CloudWriteOptions& options) {
  io_detail::write_pcd_file(path, cloud, encoding, comments, options);
}

}  // namespace primlabel
