// PLY reading/writing: round trips, property mapping, other elements, byte orders, and malformed
// input (each must raise an IoError naming the file and the problem).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "cloud_io_test_util.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using test::expect_same_attributes;
using test::kNaN;
using test::MalformedFile;
using test::put;
using test::write_bytes;
using test::xyz_floats;

template <typename T>
void put_big_endian(std::string& out, T value) {
  std::string bytes;
  put(bytes, value);
  std::reverse(bytes.begin(), bytes.end());
  out += bytes;
}

std::string ply(const std::string& format, const std::string& declarations) {
  return "ply\nformat " + format + " 1.0\n" + declarations + "end_header\n";
}

const std::string kXyzFloat = "property float x\nproperty float y\nproperty float z\n";

// The PCD tests' awkward cloud, but pixel 3 is a transparent white: alpha 0 must survive too.
PointCloud awkward_cloud() {
  PointCloud cloud = test::awkward_cloud();
  cloud.rgba[3] = 0x00ffffffu;
  return cloud;
}

void expect_read_error(const std::string& path, const std::string& needle) {
  test::expect_read_error(read_ply, path, needle);
}

// ---------------------------------------------------------------------------------------------
// Round trips

class PlyRoundTrip : public ::testing::TestWithParam<PlyEncoding> {};

TEST_P(PlyRoundTrip, EveryAttributeSurvivesBitForBitAsOneRow) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.ply");
  const PointCloud original = awkward_cloud();
  write_ply(path, original, GetParam());
  const PointCloud loaded = read_ply(path);
  EXPECT_EQ(loaded.width, 12u);  // PLY has no notion of organised clouds
  EXPECT_EQ(loaded.height, 1u);
  expect_same_attributes(original, loaded);
  ASSERT_EQ(loaded.fields.size(), 2u);
  EXPECT_EQ(loaded.fields[0].name, "fpfh");
  EXPECT_EQ(loaded.fields[0].count, 33);
}

TEST_P(PlyRoundTrip, EmptyAndXyzOnlyClouds) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.ply");
  PointCloud empty;
  write_ply(path, empty, GetParam());
  EXPECT_EQ(read_ply(path).size(), 0u);

  PointCloud cloud;
  cloud.resize_unorganized(3);
  cloud.xyz = {Vec3f(1, 2, 3), Vec3f(-1, 0.5f, kNaN), Vec3f(0, 0, 0)};
  write_ply(path, cloud, GetParam());
  const PointCloud loaded = read_ply(path);
  expect_same_attributes(cloud, loaded);
  EXPECT_FALSE(loaded.has_normals() || loaded.has_rgba() || loaded.has_labels() ||
               loaded.has_curvature());
}

INSTANTIATE_TEST_SUITE_P(BothEncodings, PlyRoundTrip,
                         ::testing::Values(PlyEncoding::kAscii, PlyEncoding::kBinaryLittleEndian),
                         [](const auto& info) {
                           return std::string(info.param == PlyEncoding::kAscii ? "Ascii"
                                                                                : "Binary");
                         });

TEST(PlyWrite, HeaderCommentsFollowTheFormatLineAndAreSkippedByTheReader) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.ply");
  const PointCloud original = awkward_cloud();
  write_cloud(path, original, {"primlabel classes 1 plane", "second"});
  std::ifstream in(path, std::ios::binary);
  std::vector<std::string> lines;
  for (std::string line; lines.size() < 5 && std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[1], "format binary_little_endian 1.0");
  EXPECT_EQ(lines[2], "comment primlabel classes 1 plane");
  EXPECT_EQ(lines[3], "comment second");
  EXPECT_EQ(lines[4], "comment written by primlabel");
  EXPECT_EQ(read_ply(path).size(), original.size());
  EXPECT_THROW(write_ply(path, original, PlyEncoding::kAscii, {"two\nlines"}),
               std::invalid_argument);
  EXPECT_EQ(read_ply(path).size(), original.size());  // the earlier file is still there
}

TEST(PlyWrite, HeaderDeclaresStandardProperties) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.ply");
  write_ply(path, awkward_cloud(), PlyEncoding::kBinaryLittleEndian);
  std::ifstream in(path, std::ios::binary);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line) && line != "end_header";) lines.push_back(line);
  const std::vector<std::string> start = {"ply",
                                          "format binary_little_endian 1.0",
                                          "comment written by primlabel",
                                          "element vertex 12",
                                          "property float x",
                                          "property float y",
                                          "property float z",
                                          "property float nx",
                                          "property float ny",
                                          "property float nz",
                                          "property float curvature",
                                          "property uint label",  // a label beyond int range
                                          "property uchar red",
                                          "property uchar green",
                                          "property uchar blue",
                                          "property uchar alpha",
                                          "property float fpfh_0"};
  ASSERT_GE(lines.size(), start.size());
  EXPECT_EQ(std::vector<std::string>(lines.begin(), lines.begin() + start.size()), start);
  EXPECT_EQ(lines[start.size() + 31], "property float fpfh_32");
  EXPECT_EQ(lines.back(), "property float intensity");
}

TEST(PlyWrite, LabelsBeyondIntRangeStayUintAndEveryLabelRoundTrips) {
  test::TempDir dir;
  PointCloud cloud;
  cloud.resize_unorganized(3);
  // Ascii too: an "int" label was once written as the float of its bits ("1e-45").
  for (const auto encoding : {PlyEncoding::kBinaryLittleEndian, PlyEncoding::kAscii})
    for (const std::uint32_t big : {0x7fffffffu, 0x80000000u}) {
      cloud.labels = {0u, 7u, big};
      const std::string path = dir.file("labels.ply");
      write_ply(path, cloud, encoding);
      std::ifstream in(path, std::ios::binary);
      std::string header, line;
      while (std::getline(in, line) && line != "end_header") header += line + "\n";
      const char* expected = big <= 0x7fffffffu ? "property int label\n" : "property uint label\n";
      EXPECT_NE(header.find(expected), std::string::npos) << header;
      EXPECT_EQ(read_ply(path).labels, cloud.labels);
    }
}

// ---------------------------------------------------------------------------------------------
// Reading files from other writers

TEST(PlyRead, BigEndianWithColourWithoutAlphaAndVariousTypes) {
  test::TempDir dir;
  const std::string path = dir.file("be.ply");
  std::string file = ply("binary_big_endian",
                         "comment from a big-endian machine\nelement vertex 2\n"
                         "property double x\nproperty float y\nproperty int z\n"
                         "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                         "property short temperature\nproperty ushort id\n");
  for (int i = 0; i < 2; ++i) {
    put_big_endian<double>(file, 0.5 + i);
    put_big_endian<float>(file, -1.25f * i);
    put_big_endian<std::int32_t>(file, -7 + i);
    file += static_cast<char>(10 + i);
    file += static_cast<char>(20 + i);
    file += static_cast<char>(250 + i);
    put_big_endian<std::int16_t>(file, static_cast<std::int16_t>(-300 - i));
    put_big_endian<std::uint16_t>(file, static_cast<std::uint16_t>(65000 + i));
  }
  write_bytes(path, file);
  const PointCloud cloud = read_ply(path);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.xyz[0], Vec3f(0.5f, -0.0f, -7.0f));
  EXPECT_EQ(cloud.xyz[1], Vec3f(1.5f, -1.25f, -6.0f));
  EXPECT_EQ(cloud.rgba, (std::vector<std::uint32_t>{0xff0a14fau, 0xff0b15fbu}));
  ASSERT_EQ(cloud.fields.size(), 2u);
  EXPECT_EQ(cloud.fields[0].name, "temperature");
  EXPECT_EQ(cloud.fields[0].values, (std::vector<float>{-300.0f, -301.0f}));
  EXPECT_EQ(cloud.fields[1].name, "id");
  EXPECT_EQ(cloud.fields[1].values, (std::vector<float>{65000.0f, 65001.0f}));
}

// A mesh-like file: an element before the vertices, a vertex list property, faces after.
std::string mesh_declarations() {
  return "element camera 2\nproperty float fov\nproperty list uchar int tags\n"
         "element vertex 3\nproperty float x\nproperty list uchar int neighbours\n"
         "property float y\nproperty float z\nproperty float normal_x\nproperty float normal_y\n"
         "property float normal_z\n"
         "element face 1\nproperty list uchar int vertex_indices\n";
}

void expect_mesh_vertices(const PointCloud& cloud) {
  ASSERT_EQ(cloud.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(cloud.xyz[i], Vec3f(i, 10 + i, 20 + i));
    EXPECT_EQ(cloud.normals[i], Vec3f(0, 0, 1));
  }
  EXPECT_TRUE(cloud.fields.empty()) << "list properties are skipped, not turned into fields";
}

TEST(PlyRead, BinarySkipsOtherElementsAndVertexLists) {
  test::TempDir dir;
  const std::string path = dir.file("mesh.ply");
  std::string file = ply("binary_little_endian", mesh_declarations());
  for (int camera = 0; camera < 2; ++camera) {
    put<float>(file, 60.0f);
    file += static_cast<char>(camera + 1);  // list lengths 1 and 2
    for (int t = 0; t <= camera; ++t) put<std::int32_t>(file, 99);
  }
  for (int i = 0; i < 3; ++i) {
    put<float>(file, static_cast<float>(i));
    file += static_cast<char>(i);  // neighbour lists of length 0, 1, 2
    for (int k = 0; k < i; ++k) put<std::int32_t>(file, k);
    for (float v : {10.0f + i, 20.0f + i, 0.0f, 0.0f, 1.0f}) put(file, v);
  }
  file += '\x03';
  for (int k = 0; k < 3; ++k) put<std::int32_t>(file, k);
  write_bytes(path, file);
  expect_mesh_vertices(read_ply(path));
}

TEST(PlyRead, AsciiSkipsOtherElementsAndVertexLists) {
  test::TempDir dir;
  const std::string path = dir.file("mesh.ply");
  write_bytes(path, ply("ascii", mesh_declarations()) +
                        "60 1 99\n60 2 99 98\n"
                        "0 0 10 20 0 0 1\n1 1 0 11 21 0 0 1\n2 2 0 1 12 22 0 0 1\n"
                        "3 0 1 2\n");
  expect_mesh_vertices(read_ply(path));
}

TEST(PlyRead, EmptyElementWithHugeCountIsSkippedInstantly) {
  test::TempDir dir;
  const std::string path = dir.file("nothing.ply");
  std::string file = ply("binary_little_endian",
                         "element nothing 18446744073709551615\nelement vertex 1\n" + kXyzFloat);
  for (float v : {1.0f, 2.0f, 3.0f}) put(file, v);
  write_bytes(path, file);
  EXPECT_EQ(read_ply(path).xyz[0], Vec3f(1, 2, 3));
}

TEST(PlyRead, IndexedPropertiesAreReassembledOnlyAsCompleteRuns) {
  test::TempDir dir;
  const std::string path = dir.file("runs.ply");
  write_bytes(path, ply("ascii", "element vertex 1\n" + kXyzFloat +
                                     "property float a_0\nproperty float a_1\nproperty float a_2\n"
                                     "property float b_0\n"
                                     "property float c_0\nproperty float c_2\n"
                                     "property float d\nproperty float d_0\nproperty float d_1\n"
                                     "property int label\n") +
                        "1 2 3 10 11 12 20 30 32 40 41 42 7\n");
  const PointCloud cloud = read_ply(path);
  std::vector<std::string> names;
  for (const FloatField& field : cloud.fields)
    names.push_back(field.name + ":" + std::to_string(field.count));
  EXPECT_EQ(names,
            (std::vector<std::string>{"a:3", "b_0:1", "c_0:1", "c_2:1", "d:1", "d_0:1", "d_1:1"}));
  EXPECT_EQ(cloud.fields[0].values, (std::vector<float>{10, 11, 12}));
  EXPECT_EQ(cloud.labels, std::vector<std::uint32_t>{7});
}

TEST(PlyRead, CrLfHeaderAndCommentsAnywhere) {
  test::TempDir dir;
  const std::string path = dir.file("crlf.ply");
  write_bytes(path,
              "ply\r\nformat ascii 1.0\r\ncomment hello\r\nelement vertex 1\r\nobj_info x\r\n"
              "property float x\r\nproperty float y\r\nproperty float z\r\nend_header\r\n"
              "1 2 3\r\n");
  EXPECT_EQ(read_ply(path).xyz[0], Vec3f(1, 2, 3));
}

// ---------------------------------------------------------------------------------------------
// Malformed input

std::vector<MalformedFile> malformed_cases() {
  const std::string vertex1 = "element vertex 1\n" + kXyzFloat;
  std::string negative_list = ply(
      "binary_little_endian", "element face 1\nproperty list char int vertex_indices\n" + vertex1);
  negative_list += '\xff';
  std::string truncated_face = ply(
      "binary_little_endian", "element face 1\nproperty list uchar int vertex_indices\n" + vertex1);
  truncated_face += '\x09';
  put<std::int32_t>(truncated_face, 1);
  std::string negative_label =
      ply("binary_little_endian", vertex1 + "property int label\n") + xyz_floats(1);
  put<std::int32_t>(negative_label, -3);

  return {
      {"EmptyFile", "", "empty file, not a PLY file"},
      {"NotPly", "PLY\nformat ascii 1.0\n", "not a PLY file (first line is 'PLY', expected 'ply')"},
      {"UnsupportedFormat", ply("binary_middle_endian", vertex1),
       "unsupported format 'binary_middle_endian'"},
      {"UnsupportedVersion", "ply\nformat ascii 2.0\n" + vertex1 + "end_header\n",
       "header line 2: unsupported PLY version '2.0'"},
      {"MissingFormat", "ply\n" + vertex1 + "end_header\n1 2 3\n",
       "header line 6: missing format line before end_header"},
      {"MissingEndHeader", "ply\nformat ascii 1.0\n" + vertex1 + "1 2 3\n",
       "header line 7: unknown header keyword '1'"},
      {"HeaderRunsOut", "ply\nformat ascii 1.0\n" + vertex1, "missing end_header line"},
      {"UnknownKeyword", ply("ascii", "elemnt vertex 1\n"),
       "header line 3: unknown header keyword 'elemnt'"},
      {"PropertyBeforeElement", ply("ascii", "property float x\n"),
       "header line 3: property before any element"},
      {"UnknownType", ply("ascii", "element vertex 1\nproperty float16 x\n"),
       "header line 4: unknown property type 'float16'"},
      {"FloatListLength", ply("ascii", vertex1 + "property list float int n\n"),
       "header line 7: list length type 'float' is not an integer type"},
      {"BadElementCount", ply("ascii", "element vertex -1\n"),
       "header line 3: element count '-1' is not a non-negative integer"},
      {"NoVertexElement", ply("ascii", "element face 0\nproperty list uchar int v\n"),
       "no 'vertex' element"},
      {"MissingZ", ply("ascii", "element vertex 1\nproperty float x\nproperty float y\n"),
       "header line 3: vertex element lacks property x, y or z"},
      {"ListCoordinate",
       ply("ascii",
           "element vertex 1\nproperty float x\nproperty float y\n"
           "property list uchar float z\n"),
       "header line 6: vertex property 'z' must not be a list"},
      {"DuplicateProperty", ply("ascii", vertex1 + "property float x\n"),
       "header line 7: vertex property 'x' is listed twice"},
      {"FloatColour",
       ply("ascii", vertex1 + "property float red\nproperty uchar green\n"
                              "property uchar blue\n"),
       "header line 7: colour property 'red' must be uchar"},
      {"VertexCountTooLarge", ply("ascii", "element vertex 5000000000\n" + kXyzFloat),
       "vertex count 5000000000 exceeds 4294967295"},
      {"TruncatedBinary",
       ply("binary_little_endian", "element vertex 3\n" + kXyzFloat) + xyz_floats(1) + "abcdefgh",
       "truncated binary data: expected 36 bytes for 3 vertices, found 20"},
      {"TruncatedBigEndian",
       ply("binary_big_endian", "element vertex 3\n" + kXyzFloat) + xyz_floats(2) + "ab",
       "truncated binary data in element 'vertex' at record 2 of 3"},
      {"TruncatedFaceBeforeVertex", truncated_face,
       "truncated binary data in element 'face' at record 0 of 1"},
      {"NegativeListLength", negative_list, "element 'face' record 0: negative length of list"},
      {"NegativeLabel", negative_label, "field 'label' of point 0: value -3 is not a label"},
      {"AsciiEndsEarly", ply("ascii", "element vertex 2\n" + kXyzFloat) + "1 2 3\n4 5\n",
       "ascii data ends after 1 of 2 'vertex' records"},
      {"AsciiNonNumeric", ply("ascii", "element vertex 2\n" + kXyzFloat) + "1 2 3\n4 abc 6\n",
       "line 9: vertex 1: property 'y': 'abc' is not a valid float"},
      {"AsciiUcharOutOfRange",
       ply("ascii", vertex1 + "property uchar red\nproperty uchar green\nproperty uchar blue\n") +
           "1 2 3 0 256 0\n",
       "line 11: vertex 0: property 'green': '256' is not a valid uchar"},
      {"AsciiBadListLength",
       ply("ascii", "element face 1\nproperty list uchar int vertex_indices\n" + vertex1) +
           "x 1 2\n1 2 3\n",
       "list length 'x' of 'vertex_indices' is not a non-negative integer"},
  };
}

class PlyMalformed : public ::testing::TestWithParam<MalformedFile> {};

TEST_P(PlyMalformed, ThrowsIoErrorNamingFileAndProblem) {
  test::expect_rejected(read_ply, GetParam(), ".ply");
}

INSTANTIATE_TEST_SUITE_P(Cases, PlyMalformed, ::testing::ValuesIn(malformed_cases()),
                         test::malformed_file_name);

TEST(PlyMalformedFiles, MissingFileReportsErrno) {
  test::TempDir dir;
  expect_read_error(dir.file("nope.ply"), "cannot open: No such file or directory");
}

// Absurd counts in tiny files must fail on the data, before allocating anything like them.
class PlyHugeHeader : public ::testing::TestWithParam<MalformedFile> {};

TEST_P(PlyHugeHeader, FailsWithoutAllocatingTheDeclaredSize) {
  test::expect_rejected_without_allocating(read_ply, GetParam(), ".ply");
}

std::vector<MalformedFile> huge_cases() {
  const std::string huge_vertex = "element vertex 4000000000\n" + kXyzFloat;
  return {
      {"Binary", ply("binary_little_endian", huge_vertex) + std::string(100, 'x'),
       "truncated binary data: expected 48000000000 bytes for 4000000000 vertices, found 100"},
      {"BigEndian", ply("binary_big_endian", huge_vertex) + std::string(100, 'x'),
       "truncated binary data in element 'vertex' at record 8 of 4000000000"},
      {"VertexWithList",
       ply("binary_little_endian", huge_vertex + "property list uchar int n\n") +
           std::string(100, '\0'),
       "truncated binary data in element 'vertex'"},
      {"Ascii", ply("ascii", huge_vertex) + "1 2 3\n4 5 6\n",
       "ascii data ends after 2 of 4000000000 'vertex' records"},
      {"FacesBeforeVertex",
       ply("binary_little_endian",
           "element face 18446744073709551615\nproperty list uchar int v\n" + huge_vertex) +
           std::string(100, '\0'),
       "truncated binary data in element 'face' at record 100 of 18446744073709551615"},
      {"FixedElementBeforeVertex",
       ply("binary_little_endian",
           "element camera 18446744073709551615\nproperty double fov\n" + huge_vertex) +
           std::string(100, '\0'),
       "truncated binary data in element 'camera'"},
  };
}

INSTANTIATE_TEST_SUITE_P(Cases, PlyHugeHeader, ::testing::ValuesIn(huge_cases()),
                         test::malformed_file_name);

}  // namespace
}  // namespace primlabel
