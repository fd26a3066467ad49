// PLY reading (ascii, binary_little_endian, binary_big_endian) and writing (ascii,
// binary_little_endian) of the vertex element as a point cloud.
//
// Reading rules: only the first `vertex` element becomes points; elements before it are parsed
// just enough to be skipped, elements after it are not read. Vertex list properties are skipped.
// Scalar properties map as x y z -> xyz, nx ny nz (or normal_x ...) -> normals, curvature,
// label, red green blue [alpha] (uchar) -> rgba; the rest become count-1 FloatFields, except
// runs name_0, name_1, ..., name_k (k >= 1) which are reassembled into one FloatField `name` of
// count k + 1 (the form write_ply gives multi-value fields such as fpfh).

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io_util.hpp"
#include "primlabel/geometry/cloud_io.hpp"

namespace primlabel::io_detail {
namespace {

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyProperty {
  std::string name;
  ScalarType type;  // the value type, or the item type of a list
  bool is_list = false;
  ScalarType list_length_type;
  int line = 0;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  int line = 0;

  bool has_lists() const {
    return std::any_of(properties.begin(), properties.end(),
                       [](const PlyProperty& p) { return p.is_list; });
  }
  // Bytes of the scalar properties of one record: the whole record when there are no lists.
  std::uint64_t scalar_bytes() const {
    std::uint64_t bytes = 0;
    for (const PlyProperty& p : properties)
      if (!p.is_list) bytes += static_cast<unsigned>(p.type.size);
    return bytes;
  }
  // Fewest bytes one binary record can occupy (lists may be empty).
  std::uint64_t min_record_bytes() const {
    std::uint64_t bytes = 0;
    for (const PlyProperty& p : properties)
      bytes += static_cast<unsigned>(p.is_list ? p.list_length_type.size : p.type.size);
    return bytes;
  }
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::size_t data_offset = 0;  // first byte after end_header
  int end_header_line = 0;
};

bool parse_ply_type(std::string_view name, ScalarType& type) {
  struct Entry {
    std::string_view name;
    ScalarType type;
  };
  static constexpr std::array<Entry, 16> kTypes = {{
      {"char", {ScalarKind::kSigned, 1}},
      {"int8", {ScalarKind::kSigned, 1}},
      {"uchar", {ScalarKind::kUnsigned, 1}},
      {"uint8", {ScalarKind::kUnsigned, 1}},
      {"short", {ScalarKind::kSigned, 2}},
      {"int16", {ScalarKind::kSigned, 2}},
      {"ushort", {ScalarKind::kUnsigned, 2}},
      {"uint16", {ScalarKind::kUnsigned, 2}},
      {"int", {ScalarKind::kSigned, 4}},
      {"int32", {ScalarKind::kSigned, 4}},
      {"uint", {ScalarKind::kUnsigned, 4}},
      {"uint32", {ScalarKind::kUnsigned, 4}},
      {"float", {ScalarKind::kFloat, 4}},
      {"float32", {ScalarKind::kFloat, 4}},
      {"double", {ScalarKind::kFloat, 8}},
      {"float64", {ScalarKind::kFloat, 8}},
  }};
  for (const Entry& entry : kTypes) {
    if (entry.name == name) {
      type = entry.type;
      return true;
    }
  }
  return false;
}

PlyHeader parse_ply_header(const std::string& path, std::string_view file) {
  auto fail_at = [&](int line, const std::string& message) {
    throw_io_error(path, cat("header line ", line, ": ", message));
  };
  PlyHeader header;
  bool have_format = false;
  std::vector<std::string_view> tokens;
  std::size_t pos = 0;
  int line_number = 0;
  while (pos < file.size()) {
    const std::size_t end_of_line = std::min(file.find('\n', pos), file.size());
    const std::string_view line = file.substr(pos, end_of_line - pos);
    pos = std::min(end_of_line + 1, file.size());
    ++line_number;
    split_whitespace(line, tokens);
    if (line_number == 1) {
      if (tokens.size() != 1 || tokens[0] != "ply")
        throw_io_error(path,
                       cat("not a PLY file (first line is ", in_quotes(line), ", expected 'ply')"));
      continue;
    }
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      if (have_format) fail_at(line_number, "duplicate format line");
      if (tokens.size() != 3) fail_at(line_number, "format needs a kind and a version");
      if (tokens[1] == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (tokens[1] == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (tokens[1] == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBigEndian;
      } else {
        throw_io_error(path, cat("unsupported format ", in_quotes(tokens[1])));
      }
      if (tokens[2] != "1.0")
        fail_at(line_number, cat("unsupported PLY version ", in_quotes(tokens[2])));
      have_format = true;
    } else if (keyword == "element") {
      if (tokens.size() != 3) fail_at(line_number, "element needs a name and a count");
      PlyElement element{std::string(tokens[1]), 0, {}, line_number};
      if (!parse_integer(tokens[2], element.count))
        fail_at(line_number,
                cat("element count ", in_quotes(tokens[2]), " is not a non-negative integer"));
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty()) fail_at(line_number, "property before any element");
      PlyProperty property;
      property.line = line_number;
      if (tokens.size() == 5 && tokens[1] == "list") {
        property.is_list = true;
        if (!parse_ply_type(tokens[2], property.list_length_type) ||
            !property.list_length_type.is_integer())
          fail_at(line_number,
                  cat("list length type ", in_quotes(tokens[2]), " is not an integer type"));
        if (!parse_ply_type(tokens[3], property.type))
          fail_at(line_number, cat("unknown property type ", in_quotes(tokens[3])));
        property.name = tokens[4];
      } else if (tokens.size() == 3) {
        if (!parse_ply_type(tokens[1], property.type))
          fail_at(line_number, cat("unknown property type ", in_quotes(tokens[1])));
        property.name = tokens[2];
      } else {
        fail_at(line_number, "property needs a type and a name");
      }
      header.elements.back().properties.push_back(std::move(property));
    } else if (keyword == "end_header") {
      if (!have_format) fail_at(line_number, "missing format line before end_header");
      header.data_offset = pos;
      header.end_header_line = line_number;
      return header;
    } else {
      fail_at(line_number, cat("unknown header keyword ", in_quotes(keyword)));
    }
  }
  if (file.empty()) throw_io_error(path, "empty file, not a PLY file");
  throw_io_error(path, "header: missing end_header line");
}

// How the vertex properties map onto PointCloud members (indices into the vertex properties).
struct VertexPlan {
  std::array<int, 3> xyz{-1, -1, -1};
  std::array<int, 3> normal{-1, -1, -1};
  int curvature = -1;
  int label = -1;
  std::array<int, 4> colour{-1, -1, -1, -1};  // red, green, blue, alpha
};

VertexPlan plan_vertex(const std::string& path, const PlyElement& vertex) {
  const std::vector<PlyProperty>& properties = vertex.properties;
  auto fail_at = [&](int line, const std::string& message) {
    throw_io_error(path, cat("header line ", line, ": ", message));
  };
  for (std::size_t i = 0; i < properties.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (properties[i].name == properties[j].name)
        fail_at(properties[i].line,
                cat("vertex property ", in_quotes(properties[i].name), " is listed twice"));

  auto scalar_index = [&](std::string_view name) -> int {
    for (std::size_t i = 0; i < properties.size(); ++i) {
      if (properties[i].name != name) continue;
      if (properties[i].is_list)
        fail_at(properties[i].line,
                cat("vertex property ", in_quotes(name), " must not be a list"));
      return static_cast<int>(i);
    }
    return -1;
  };
  auto all_present = [](const auto& indices) {
    return std::all_of(indices.begin(), indices.end(), [](int i) { return i >= 0; });
  };

  VertexPlan plan;
  plan.xyz = {scalar_index("x"), scalar_index("y"), scalar_index("z")};
  if (!all_present(plan.xyz)) fail_at(vertex.line, "vertex element lacks property x, y or z");
  plan.normal = {scalar_index("nx"), scalar_index("ny"), scalar_index("nz")};
  if (!all_present(plan.normal))
    plan.normal = {scalar_index("normal_x"), scalar_index("normal_y"), scalar_index("normal_z")};
  if (!all_present(plan.normal)) plan.normal = {-1, -1, -1};
  plan.curvature = scalar_index("curvature");
  plan.label = scalar_index("label");

  const std::array<int, 3> rgb = {scalar_index("red"), scalar_index("green"), scalar_index("blue")};
  if (all_present(rgb)) {
    plan.colour = {rgb[0], rgb[1], rgb[2], scalar_index("alpha")};
    for (const int index : plan.colour) {
      if (index < 0) continue;
      const PlyProperty& p = properties[index];
      if (p.type.kind != ScalarKind::kUnsigned || p.type.size != 1)
        fail_at(p.line, cat("colour property ", in_quotes(p.name), " must be uchar"));
    }
  }
  return plan;
}

template <typename T>
T load_ordered(const unsigned char* bytes, bool big_endian) {
  unsigned char copy[sizeof(T)];
  std::memcpy(copy, bytes, sizeof(T));
  if (big_endian) std::reverse(copy, copy + sizeof(T));
  return load_scalar<T>(copy);
}

// Reads a list length stored as `type`; lengths must be non-negative.
std::optional<std::uint64_t> load_list_length(ScalarType type, const unsigned char* bytes,
                                              bool big_endian) {
  return visit_scalar_type(type, [&](auto tag) -> std::optional<std::uint64_t> {
    using T = typename decltype(tag)::type;
    if constexpr (std::is_floating_point_v<T>) {
      return std::nullopt;  // excluded when the header is parsed
    } else {
      const T value = load_ordered<T>(bytes, big_endian);
      if (value < 0) return std::nullopt;
      return static_cast<std::uint64_t>(value);
    }
  });
}

// Walks binary records, calling on_scalar(property_index, bytes) for every scalar value and
// skipping lists. Every access is bounds-checked against `data`; `pos` is advanced.
class BinaryRecordWalker {
 public:
  BinaryRecordWalker(const std::string& path, std::string_view data, bool big_endian)
      : path_(path),
        data_(reinterpret_cast<const unsigned char*>(data.data())),
        size_(data.size()),
        big_endian_(big_endian) {}

  std::size_t pos() const { return pos_; }
  void advance(std::size_t bytes) { pos_ += bytes; }
  std::size_t remaining() const { return size_ - pos_; }
  const unsigned char* here() const { return data_ + pos_; }

  template <typename OnScalar>
  void walk(const PlyElement& element, std::uint64_t record, OnScalar&& on_scalar) {
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& property = element.properties[p];
      if (!property.is_list) {
        require(property.type.size, element, record);
        on_scalar(p, data_ + pos_);
        pos_ += property.type.size;
        continue;
      }
      require(property.list_length_type.size, element, record);
      const std::optional<std::uint64_t> length =
          load_list_length(property.list_length_type, data_ + pos_, big_endian_);
      if (!length)
        throw_io_error(path_, cat("element ", in_quotes(element.name), " record ", record,
                                  ": negative length of list ", in_quotes(property.name)));
      pos_ += property.list_length_type.size;
      std::uint64_t bytes = 0;
      if (!multiply_fits(*length, property.type.size, bytes) || bytes > remaining())
        truncated(element, record);
      pos_ += bytes;
    }
  }

  [[noreturn]] void truncated(const PlyElement& element, std::uint64_t record) const {
    throw_io_error(path_, cat("truncated binary data in element ", in_quotes(element.name),
                              " at record ", record, " of ", element.count));
  }

 private:
  void require(int bytes, const PlyElement& element, std::uint64_t record) const {
    if (static_cast<std::size_t>(bytes) > remaining()) truncated(element, record);
  }

  const std::string& path_;
  const unsigned char* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  bool big_endian_;
};

void skip_binary_element(BinaryRecordWalker& walker, const PlyElement& element) {
  if (element.properties.empty()) return;  // records of no bytes: nothing to skip
  if (!element.has_lists()) {
    std::uint64_t bytes = 0;
    if (!multiply_fits(element.count, element.scalar_bytes(), bytes) || bytes > walker.remaining())
      walker.truncated(element, walker.remaining() / element.scalar_bytes());
    walker.advance(bytes);
    return;
  }
  // Every record takes at least one byte, so this loop ends at the end of the data.
  for (std::uint64_t record = 0; record < element.count; ++record)
    walker.walk(element, record, [](std::size_t, const unsigned char*) {});
}

// Offsets of the scalar vertex properties inside a packed record of scalars only.
std::vector<std::size_t> scalar_offsets(const PlyElement& vertex) {
  std::vector<std::size_t> offsets(vertex.properties.size(), 0);
  std::size_t offset = 0;
  for (std::size_t p = 0; p < vertex.properties.size(); ++p) {
    offsets[p] = offset;
    if (!vertex.properties[p].is_list) offset += vertex.properties[p].type.size;
  }
  return offsets;
}

// Copies binary vertex records into packed little-endian records of their scalar properties
// (used for big-endian files and for vertices carrying lists).
std::vector<unsigned char> pack_binary_vertices(BinaryRecordWalker& walker,
                                                const PlyElement& vertex, bool big_endian) {
  const std::uint64_t record_bytes = vertex.scalar_bytes();
  const std::vector<std::size_t> offsets = scalar_offsets(vertex);
  std::vector<unsigned char> records;
  records.reserve(
      std::min<std::uint64_t>(vertex.count, walker.remaining() / vertex.min_record_bytes()) *
      record_bytes);
  for (std::uint64_t v = 0; v < vertex.count; ++v) {
    const std::size_t start = records.size();
    records.resize(start + record_bytes);
    walker.walk(vertex, v, [&](std::size_t p, const unsigned char* bytes) {
      unsigned char* out = records.data() + start + offsets[p];
      const int size = vertex.properties[p].type.size;
      std::memcpy(out, bytes, size);
      if (big_endian) std::reverse(out, out + size);
    });
  }
  return records;
}

// Whitespace-separated tokens of ascii PLY data, with line numbers for messages.
class AsciiTokens {
 public:
  AsciiTokens(std::string_view text, int first_line) : text_(text), line_(first_line) {}

  bool next(std::string_view& token) {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ == text_.size()) return false;
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    token = text_.substr(start, pos_ - start);
    return true;
  }
  int line() const { return line_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  int line_;
};

// Reads ascii records, calling on_scalar(property_index, token) for every scalar value and
// skipping lists. `what` names the record in messages (e.g. "vertex 12").
class AsciiRecordReader {
 public:
  AsciiRecordReader(const std::string& path, AsciiTokens& tokens) : path_(path), tokens_(tokens) {}

  template <typename OnScalar>
  void read(const PlyElement& element, std::uint64_t record, OnScalar&& on_scalar) {
    std::string_view token;
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& property = element.properties[p];
      if (!tokens_.next(token)) ended(element, record);
      if (!property.is_list) {
        on_scalar(p, token);
        continue;
      }
      std::uint64_t length = 0;
      if (!parse_integer(token, length))
        throw_io_error(path_, cat("line ", tokens_.line(), ": element ", in_quotes(element.name),
                                  " record ", record, ": list length ", in_quotes(token), " of ",
                                  in_quotes(property.name), " is not a non-negative integer"));
      // Each skipped item consumes a token, so a huge length ends with the data.
      for (std::uint64_t i = 0; i < length; ++i)
        if (!tokens_.next(token)) ended(element, record);
    }
  }

  [[noreturn]] void ended(const PlyElement& element, std::uint64_t record) const {
    throw_io_error(path_, cat("ascii data ends after ", record, " of ", element.count, " ",
                              in_quotes(element.name), " records"));
  }

 private:
  const std::string& path_;
  AsciiTokens& tokens_;
};

std::string ply_type_name(ScalarType type) {
  switch (type.kind) {
    case ScalarKind::kFloat:
      return type.size == 8 ? "double" : "float";
    case ScalarKind::kSigned:
      return type.size == 1 ? "char" : type.size == 2 ? "short" : type.size == 4 ? "int" : "int64";
    case ScalarKind::kUnsigned:
    default:
      return type.size == 1   ? "uchar"
             : type.size == 2 ? "ushort"
             : type.size == 4 ? "uint"
                              : "uint64";
  }
}

std::vector<unsigned char> parse_ascii_vertices(const std::string& path, AsciiTokens& tokens,
                                                const PlyElement& vertex) {
  const std::uint64_t record_bytes = vertex.scalar_bytes();
  const std::vector<std::size_t> offsets = scalar_offsets(vertex);
  AsciiRecordReader reader(path, tokens);
  std::vector<unsigned char> records;
  for (std::uint64_t v = 0; v < vertex.count; ++v) {
    const std::size_t start = records.size();
    records.resize(start + record_bytes);
    reader.read(vertex, v, [&](std::size_t p, std::string_view token) {
      const PlyProperty& property = vertex.properties[p];
      bool ok = visit_scalar_type(property.type, [&](auto tag) {
        using T = typename decltype(tag)::type;
        T value{};
        const bool parsed = std::is_floating_point_v<T> ? parse_floating(token, value)
                                                        : parse_integer(token, value);
        if (parsed) std::memcpy(records.data() + start + offsets[p], &value, sizeof value);
        return parsed;
      });
      if (!ok)
        throw_io_error(path, cat("line ", tokens.line(), ": vertex ", v, ": property ",
                                 in_quotes(property.name), ": ", in_quotes(token),
                                 " is not a valid ", ply_type_name(property.type)));
    });
  }
  return records;
}

// Splits "name_12" into ("name", 12); false when the name has no numeric suffix.
bool split_indexed_name(std::string_view name, std::string_view& base, std::size_t& index) {
  const std::size_t underscore = name.rfind('_');
  if (underscore == std::string_view::npos || underscore == 0 || underscore + 1 == name.size())
    return false;
  const std::string_view digits = name.substr(underscore + 1);
  if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return false;
  if (!parse_integer(digits, index)) return false;
  base = name.substr(0, underscore);
  return true;
}

PointCloud assemble_ply_cloud(const std::string& path, const PlyElement& vertex,
                              const VertexPlan& plan, const unsigned char* records) {
  const std::size_t n = vertex.count;
  const std::vector<std::size_t> offsets = scalar_offsets(vertex);
  const std::size_t record_bytes = vertex.scalar_bytes();
  const std::vector<PlyProperty>& properties = vertex.properties;
  auto column = [&](int p) {
    return Column{advance(records, offsets[p]), record_bytes, properties[p].type};
  };

  PointCloud cloud;
  cloud.width = static_cast<std::uint32_t>(n);
  cloud.height = 1;
  std::vector<bool> consumed(properties.size(), false);
  for (std::size_t p = 0; p < properties.size(); ++p) consumed[p] = properties[p].is_list;

  cloud.xyz.resize(n);
  for (int axis = 0; axis < 3; ++axis) {
    for_each_float(column(plan.xyz[axis]), n, 0,
                   [&](std::size_t i, float v) { cloud.xyz[i][axis] = v; });
    consumed[plan.xyz[axis]] = true;
  }
  if (plan.normal[0] >= 0) {
    cloud.normals.resize(n);
    for (int axis = 0; axis < 3; ++axis) {
      for_each_float(column(plan.normal[axis]), n, 0,
                     [&](std::size_t i, float v) { cloud.normals[i][axis] = v; });
      consumed[plan.normal[axis]] = true;
    }
  }
  if (plan.curvature >= 0) {
    cloud.curvature.resize(n);
    for_each_float(column(plan.curvature), n, 0,
                   [&](std::size_t i, float v) { cloud.curvature[i] = v; });
    consumed[plan.curvature] = true;
  }
  if (plan.label >= 0) {
    cloud.labels.resize(n);
    decode_labels(path, "label", column(plan.label), n, cloud.labels.data());
    consumed[plan.label] = true;
  }
  if (plan.colour[0] >= 0) {
    // Packed as PCL does: 0xAARRGGBB; files without alpha are opaque.
    cloud.rgba.assign(n, plan.colour[3] >= 0 ? 0u : 0xff000000u);
    constexpr std::array<int, 4> kShift = {16, 8, 0, 24};
    for (int channel = 0; channel < 4; ++channel) {
      const int p = plan.colour[channel];
      if (p < 0) continue;
      const unsigned char* in = advance(records, offsets[p]);
      for (std::size_t i = 0; i < n; ++i, in += record_bytes)
        cloud.rgba[i] |= std::uint32_t{*in} << kShift[channel];
      consumed[p] = true;
    }
  }

  auto name_taken = [&](std::string_view name) {
    return std::any_of(properties.begin(), properties.end(),
                       [&](const PlyProperty& p) { return p.name == name; });
  };
  for (std::size_t p = 0; p < properties.size(); ++p) {
    if (consumed[p]) continue;
    // A run base_0, base_1, ... of at least two scalars is one multi-value field.
    std::string_view base;
    std::size_t index = 0;
    std::size_t run = 1;
    if (split_indexed_name(properties[p].name, base, index) && index == 0 && !name_taken(base)) {
      while (p + run < properties.size() && !consumed[p + run] &&
             properties[p + run].name == cat(base, '_', run))
        ++run;
    }
    if (run < 2) base = properties[p].name;
    FloatField field{std::string(base), static_cast<int>(run), {}};
    field.values.resize(n * run);
    for (std::size_t e = 0; e < run; ++e) {
      for_each_float(column(static_cast<int>(p + e)), n, 0,
                     [&](std::size_t i, float v) { field.values[i * run + e] = v; });
      consumed[p + e] = true;
    }
    cloud.fields.push_back(std::move(field));
  }
  return cloud;
}

PointCloud read_ply_file(const std::string& path) {
  const std::string file = read_whole_file(path);
  const PlyHeader header = parse_ply_header(path, file);
  const auto vertex_it = std::find_if(header.elements.begin(), header.elements.end(),
                                      [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex_it == header.elements.end()) throw_io_error(path, "no 'vertex' element");
  const PlyElement& vertex = *vertex_it;
  if (vertex.count > 0xffffffffu)
    throw_io_error(path, cat("vertex count ", vertex.count, " exceeds 4294967295"));
  const VertexPlan plan = plan_vertex(path, vertex);
  const std::string_view data = std::string_view(file).substr(header.data_offset);

  if (header.format == PlyFormat::kAscii) {
    AsciiTokens tokens(data, header.end_header_line + 1);
    AsciiRecordReader skipper(path, tokens);
    for (auto it = header.elements.begin(); it != vertex_it; ++it) {
      if (it->properties.empty()) continue;
      for (std::uint64_t record = 0; record < it->count; ++record)
        skipper.read(*it, record, [](std::size_t, std::string_view) {});
    }
    const std::vector<unsigned char> records = parse_ascii_vertices(path, tokens, vertex);
    return assemble_ply_cloud(path, vertex, plan, records.data());
  }

  const bool big_endian = header.format == PlyFormat::kBinaryBigEndian;
  BinaryRecordWalker walker(path, data, big_endian);
  for (auto it = header.elements.begin(); it != vertex_it; ++it) skip_binary_element(walker, *it);

  if (!big_endian && !vertex.has_lists()) {
    // The common case: fixed-size little-endian records are decoded in place.
    std::uint64_t bytes = 0;
    if (!multiply_fits(vertex.count, vertex.scalar_bytes(), bytes) || bytes > walker.remaining())
      throw_io_error(path,
                     cat("truncated binary data: expected ",
                         bytes ? cat(bytes) : cat(vertex.count, " x ", vertex.scalar_bytes()),
                         " bytes for ", vertex.count, " vertices, found ", walker.remaining()));
    return assemble_ply_cloud(path, vertex, plan, walker.here());
  }
  const std::vector<unsigned char> records = pack_binary_vertices(walker, vertex, big_endian);
  return assemble_ply_cloud(path, vertex, plan, records.data());
}

// ---------------------------------------------------------------------------------------------
// Writing

// One written property: `size` bytes at base + offset + i * point_stride for vertex i.
struct OutputProperty {
  std::string name;
  const char* type = "float";  // float, uint or uchar
  int size = 4;
  const unsigned char* base = nullptr;
  std::size_t offset = 0;
  std::size_t point_stride = 0;

  const unsigned char* point(std::size_t i) const { return base + offset + i * point_stride; }
};

std::vector<OutputProperty> output_properties(const PointCloud& cloud) {
  std::vector<OutputProperty> out;
  auto bytes = [](const auto* pointer) { return reinterpret_cast<const unsigned char*>(pointer); };
  const char* axes[3] = {"x", "y", "z"};
  const char* normal_axes[3] = {"nx", "ny", "nz"};
  for (int axis = 0; axis < 3; ++axis)
    out.push_back({axes[axis], "float", 4, bytes(cloud.xyz.data()), 4u * axis, sizeof(Vec3f)});
  if (cloud.has_normals())
    for (int axis = 0; axis < 3; ++axis)
      out.push_back(
          {normal_axes[axis], "float", 4, bytes(cloud.normals.data()), 4u * axis, sizeof(Vec3f)});
  if (cloud.has_curvature())
    out.push_back({"curvature", "float", 4, bytes(cloud.curvature.data()), 0, 4});
  if (cloud.has_labels()) {
    // "int" while every label fits: Open3D's PLY reader refuses "uint" attributes. Same bytes.
    const bool fits_int = std::all_of(cloud.labels.begin(), cloud.labels.end(),
                                      [](std::uint32_t l) { return l <= 0x7fffffffu; });
    out.push_back({"label", fits_int ? "int" : "uint", 4, bytes(cloud.labels.data()), 0, 4});
  }
  if (cloud.has_rgba()) {
    // Byte offsets of the channels of a little-endian 0xAARRGGBB word.
    const auto* rgba = bytes(cloud.rgba.data());
    out.push_back({"red", "uchar", 1, rgba, 2, 4});
    out.push_back({"green", "uchar", 1, rgba, 1, 4});
    out.push_back({"blue", "uchar", 1, rgba, 0, 4});
    out.push_back({"alpha", "uchar", 1, rgba, 3, 4});
  }
  for (const FloatField& field : cloud.fields) {
    const std::size_t stride = 4 * static_cast<std::size_t>(field.count);
    if (field.count == 1) {
      out.push_back({field.name, "float", 4, bytes(field.values.data()), 0, stride});
      continue;
    }
    for (int e = 0; e < field.count; ++e)
      out.push_back({cat(field.name, '_', e), "float", 4, bytes(field.values.data()),
                     4u * static_cast<std::size_t>(e), stride});
  }
  return out;
}

void write_ply_file(const std::string& path, const PointCloud& cloud, PlyEncoding encoding,
                    const HeaderComments& comments) {
  validate_cloud_for_writing(path, cloud);
  const std::vector<OutputProperty> properties = output_properties(cloud);
  std::vector<std::string> names;
  for (const OutputProperty& property : properties) names.push_back(property.name);
  check_unique_names(path, names);

  const std::size_t n = cloud.size();
  std::string out = "ply\nformat ";
  out += encoding == PlyEncoding::kAscii ? "ascii" : "binary_little_endian";
  out += " 1.0\n";
  append_comment_lines(out, "comment ", comments);
  out += cat("comment written by primlabel\nelement vertex ", n, "\n");
  std::size_t record_bytes = 0;
  for (const OutputProperty& property : properties) {
    out += cat("property ", property.type, " ", property.name, "\n");
    record_bytes += property.size;
  }
  out += "end_header\n";

  if (encoding == PlyEncoding::kAscii) {
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t p = 0; p < properties.size(); ++p) {
        const OutputProperty& property = properties[p];
        if (p > 0) out += ' ';
        if (property.size == 1)
          append_integer(out, unsigned{*property.point(i)});
        else if (property.type[0] == 'u' || property.type[0] == 'i')  // labels: uint or int
          append_integer(out, load_scalar<std::uint32_t>(property.point(i)));
        else
          append_floating(out, load_scalar<float>(property.point(i)));
      }
      out += '\n';
    }
  } else {
    const std::size_t start = out.size();
    out.resize(start + n * record_bytes);
    auto* record = reinterpret_cast<unsigned char*>(out.data() + start);
    for (std::size_t i = 0; i < n; ++i) {
      for (const OutputProperty& property : properties) {
        std::memcpy(record, property.point(i), property.size);
        record += property.size;
      }
    }
  }
  write_file_atomically(path, out);
}

}  // namespace
}  // namespace primlabel::io_detail

namespace primlabel {

PointCloud read_ply(const std::string& path) { return io_detail::read_ply_file(path); }

void write_ply(const std::string& path, const PointCloud& cloud, PlyEncoding encoding,
               const HeaderComments& comments) {
  io_detail::write_ply_file(path, cloud, encoding, comments);
}

}  // namespace primlabel
