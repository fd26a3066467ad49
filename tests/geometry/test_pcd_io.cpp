// PCD reading/writing: round trips of every encoding, PCL-written files, field layouts and types,
// and malformed input (each must raise an IoError naming the file and the problem).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "cloud_io_test_util.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using test::awkward_cloud;
using test::expect_same_attributes;
using test::kInf;
using test::kNaN;
using test::MalformedFile;
using test::put;
using test::write_bytes;

// A valid LZF stream made only of literal runs (control byte n < 32 copies n + 1 bytes), so the
// tests can build binary_compressed files without linking liblzf.
std::string lzf_literals(const std::string& bytes) {
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 32) {
    const std::size_t run = std::min<std::size_t>(32, bytes.size() - i);
    out += static_cast<char>(run - 1);
    out += bytes.substr(i, run);
  }
  return out;
}

std::string compressed_payload(const std::string& planes) {
  std::string out;
  const std::string lzf = lzf_literals(planes);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(lzf.size()));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(planes.size()));
  return out + lzf;
}

void expect_same_cloud(const PointCloud& a, const PointCloud& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_TRUE(a.viewpoint.origin == b.viewpoint.origin);
  EXPECT_TRUE(a.viewpoint.orientation.coeffs() == b.viewpoint.orientation.coeffs());
  expect_same_attributes(a, b);
}

void expect_read_error(const std::string& path, const std::string& needle) {
  test::expect_read_error(read_pcd, path, needle);
}

std::string header(const std::string& fields, const std::string& sizes, const std::string& types,
                   const std::string& counts, std::uint64_t points, const std::string& data) {
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " + fields + "\nSIZE " +
         sizes + "\nTYPE " + types + "\nCOUNT " + counts + "\nWIDTH " + std::to_string(points) +
         "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(points) + "\nDATA " +
         data + "\n";
}

std::string xyz_header(std::uint64_t points, const std::string& data) {
  return header("x y z", "4 4 4", "F F F", "1 1 1", points, data);
}

// The header of a one-point ascii file with this field layout.
std::string ascii_header(const std::string& fields, const std::string& sizes,
                         const std::string& types, const std::string& counts) {
  return header(fields, sizes, types, counts, 1, "ascii");
}

// An ascii file of x y z and a label of this SIZE and TYPE, then the data lines.
std::string ascii_with_label(const std::string& size, const std::string& type, std::uint64_t points,
                             const std::string& lines) {
  return header("x y z label", "4 4 4 " + size, "F F F " + type, "1 1 1 1", points, "ascii") +
         lines;
}

// ---------------------------------------------------------------------------------------------
// Round trips

class PcdRoundTrip : public ::testing::TestWithParam<PcdEncoding> {};

TEST_P(PcdRoundTrip, EveryAttributeSurvivesBitForBit) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.pcd");
  const PointCloud original = awkward_cloud();
  write_pcd(path, original, GetParam());
  const PointCloud loaded = read_pcd(path);
  expect_same_cloud(original, loaded);
  EXPECT_EQ(loaded.fields[0].name, "fpfh");
  EXPECT_EQ(loaded.fields[0].count, 33);
}

TEST_P(PcdRoundTrip, EmptyCloud) {
  test::TempDir dir;
  const std::string path = dir.file("empty.pcd");
  PointCloud empty;
  empty.set_field("fpfh", 33);
  write_pcd(path, empty, GetParam());
  const PointCloud loaded = read_pcd(path);
  EXPECT_EQ(loaded.size(), 0u);
  ASSERT_EQ(loaded.fields.size(), 1u);
  EXPECT_EQ(loaded.fields[0].count, 33);
}

TEST_P(PcdRoundTrip, XyzOnlyCloudHasNoOptionalAttributes) {
  test::TempDir dir;
  const std::string path = dir.file("xyz.pcd");
  PointCloud cloud;
  cloud.resize_unorganized(5);
  for (int i = 0; i < 5; ++i) cloud.xyz[i] = Vec3f(i, 2.0f * i, -i);
  write_pcd(path, cloud, GetParam());
  const PointCloud loaded = read_pcd(path);
  expect_same_cloud(cloud, loaded);
  EXPECT_FALSE(loaded.has_normals() || loaded.has_curvature() || loaded.has_labels() ||
               loaded.has_rgba());
  EXPECT_TRUE(loaded.fields.empty());
}

constexpr PcdEncoding kEncodings[] = {PcdEncoding::kAscii, PcdEncoding::kBinary,
                                      PcdEncoding::kBinaryCompressed};

std::string encoding_name(const ::testing::TestParamInfo<PcdEncoding>& info) {
  switch (info.param) {
    case PcdEncoding::kAscii:
      return "Ascii";
    case PcdEncoding::kBinary:
      return "Binary";
    default:
      return "BinaryCompressed";
  }
}

INSTANTIATE_TEST_SUITE_P(AllEncodings, PcdRoundTrip, ::testing::ValuesIn(kEncodings),
                         encoding_name);

TEST(PcdWrite, HeaderListsFieldsLikePcl) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.pcd");
  write_pcd(path, awkward_cloud(), PcdEncoding::kBinaryCompressed);
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::vector<std::string> lines;
  while (std::getline(in, line) && lines.size() < 11) lines.push_back(line);
  ASSERT_EQ(lines.size(), 11u);
  EXPECT_EQ(lines[1], "VERSION 0.7");
  // fpfh as PCL has it (COUNT 33), then its values again as scalar columns for Open3D.
  std::string copies, sizes, types, counts;
  for (int e = 0; e < 33; ++e) {
    copies += " fpfh_" + std::to_string(e);
    sizes += " 4";
    types += " F";
    counts += " 1";
  }
  EXPECT_EQ(lines[2],
            "FIELDS x y z normal_x normal_y normal_z curvature label rgba fpfh intensity" + copies);
  EXPECT_EQ(lines[3], "SIZE 4 4 4 4 4 4 4 4 4 4 4" + sizes);
  EXPECT_EQ(lines[4], "TYPE F F F F F F F U U F F" + types);
  EXPECT_EQ(lines[5], "COUNT 1 1 1 1 1 1 1 1 1 33 1" + counts);
  EXPECT_EQ(lines[6], "WIDTH 4");
  EXPECT_EQ(lines[7], "HEIGHT 3");
  EXPECT_EQ(lines[8], "VIEWPOINT 0.25 -1.5 3 0.5 0.5 -0.5 0.5");
  EXPECT_EQ(lines[9], "POINTS 12");
  EXPECT_EQ(lines[10], "DATA binary_compressed");
}

// The scalar columns of a multi-value field hold its values and fold back into it on reading.
TEST(PcdWrite, MultiValueFieldsAlsoGoOutAsScalarColumns) {
  test::TempDir dir;
  PointCloud cloud;
  cloud.xyz = {{0, 0, 0}, {1, 2, 3}};
  cloud.set_field("fpfh", 3).values = {1, 2, 3, 4, 5, 6};
  const std::string path = dir.file("cloud.pcd");
  write_pcd(path, cloud, PcdEncoding::kAscii);
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(text.find("FIELDS x y z fpfh fpfh_0 fpfh_1 fpfh_2\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\n0 0 0 1 2 3 1 2 3\n1 2 3 4 5 6 4 5 6\n"), std::string::npos) << text;
  const PointCloud back = read_pcd(path);
  ASSERT_EQ(back.fields.size(), 1u);
  EXPECT_EQ(back.fields[0].name, "fpfh");
  EXPECT_EQ(back.fields[0].values, cloud.fields[0].values);
}

TEST(PcdWrite, NoScalarColumnsWhereTheirNamesAreTaken) {
  test::TempDir dir;
  PointCloud cloud;
  cloud.xyz = {{0, 0, 0}};
  cloud.set_field("fpfh", 2).values = {1, 2};
  cloud.set_field("fpfh_1", 1).values = {7};  // the user's own column of that name
  const std::string path = dir.file("cloud.pcd");
  write_pcd(path, cloud, PcdEncoding::kAscii);
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(text.find("FIELDS x y z fpfh fpfh_1\n"), std::string::npos) << text;
}

// A column named like a copy but beyond the field's COUNT is a field of its own.
TEST(PcdRead, OnlyColumnsWithinTheCountAreFoldedBack) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.pcd");
  write_bytes(path,
              "VERSION 0.7\nFIELDS x y z h h_1 h_2\nSIZE 4 4 4 4 4 4\nTYPE F F F F F F\n"
              "COUNT 1 1 1 2 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n0 0 0 1 2 2 9\n");
  const PointCloud cloud = read_pcd(path);
  ASSERT_EQ(cloud.fields.size(), 2u);
  EXPECT_EQ(cloud.fields[0].name, "h");
  EXPECT_EQ(cloud.fields[1].name, "h_2");
  EXPECT_EQ(cloud.fields[1].values, std::vector<float>{9});
}

TEST_P(PcdRoundTrip, HeaderCommentsFollowTheFirstLineAndAreSkippedByTheReader) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.pcd");
  const PointCloud original = awkward_cloud();
  write_pcd(path, original, GetParam(), {"primlabel model tabletop", "a second line"});
  std::ifstream in(path, std::ios::binary);
  std::vector<std::string> lines;
  for (std::string line; lines.size() < 4 && std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[1], "# primlabel model tabletop");
  EXPECT_EQ(lines[2], "# a second line");
  EXPECT_EQ(lines[3], "VERSION 0.7");
  expect_same_cloud(original, read_pcd(path));
}

TEST(PcdWrite, AMultiLineHeaderCommentIsRefusedAndNothingIsWritten) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.pcd");
  EXPECT_THROW(write_pcd(path, awkward_cloud(), PcdEncoding::kBinary, {"one\nPOINTS 5"}),
               std::invalid_argument);
  EXPECT_THROW(write_cloud(path, awkward_cloud(), {"cr\r"}), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(PcdWrite, AsciiWritesNanAsNan) {
  test::TempDir dir;
  const std::string path = dir.file("nan.pcd");
  PointCloud cloud;
  cloud.resize_unorganized(1);
  cloud.xyz[0] = Vec3f(kNaN, -kNaN, 0.1f);
  write_pcd(path, cloud, PcdEncoding::kAscii);
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line)) last = line;
  EXPECT_EQ(last, "nan nan 0.1");
}

TEST(PcdWrite, ReplacesAnExistingFileAndLeavesNoTemporaryFiles) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.pcd");
  write_bytes(path, "old contents");
  write_pcd(path, awkward_cloud());
  EXPECT_EQ(read_pcd(path).size(), 12u);
  int files = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::filesystem::path(path).parent_path())) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);
}

TEST(PcdWrite, InvalidCloudIsRejectedAndLeavesTheOldFileAlone) {
  test::TempDir dir;
  const std::string path = dir.file("cloud.pcd");
  write_bytes(path, "old contents");
  PointCloud cloud = awkward_cloud();
  cloud.normals.pop_back();
  try {
    write_pcd(path, cloud);
    ADD_FAILURE() << "no IoError";
  } catch (const IoError& error) {
    EXPECT_NE(std::string(error.what()).find("normals has 11 entries for 12 points"),
              std::string::npos)
        << error.what();
  }
  std::ifstream in(path);
  std::string contents;
  std::getline(in, contents);
  EXPECT_EQ(contents, "old contents");
}

TEST(PcdWrite, RejectsBadFieldsAndShapes) {
  test::TempDir dir;
  const std::string path = dir.file("bad.pcd");
  {
    PointCloud cloud = awkward_cloud();
    cloud.fields[0].values.pop_back();
    EXPECT_THROW(write_pcd(path, cloud), IoError);
  }
  {
    PointCloud cloud = awkward_cloud();
    cloud.set_field("x", 1);  // would duplicate the coordinate field
    EXPECT_THROW(write_pcd(path, cloud), IoError);
  }
  {
    PointCloud cloud = awkward_cloud();
    cloud.set_field("has space", 1);
    EXPECT_THROW(write_pcd(path, cloud), IoError);
  }
  {
    PointCloud cloud = awkward_cloud();
    cloud.width = 5;  // 5 x 3 != 12
    EXPECT_THROW(write_pcd(path, cloud), IoError);
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_THROW(write_pcd(dir.file("missing_dir/cloud.pcd"), awkward_cloud()), IoError);
}

// ---------------------------------------------------------------------------------------------
// Files written by PCL

TEST(PcdSharedData, BunnyAsciiWithNormalsAndCurvature) {
  const std::string path = test::shared_data("pcl/bun0.pcd");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  const PointCloud cloud = read_pcd(path);
  ASSERT_EQ(cloud.size(), 397u);
  EXPECT_EQ(cloud.width, 397u);
  EXPECT_EQ(cloud.height, 1u);
  ASSERT_TRUE(cloud.has_normals());
  ASSERT_TRUE(cloud.has_curvature());
  EXPECT_FALSE(cloud.has_labels() || cloud.has_rgba());
  EXPECT_TRUE(cloud.fields.empty());
  EXPECT_EQ(cloud.xyz[0], Vec3f(0.0054215998f, 0.11349f, 0.040748999f));
  EXPECT_EQ(cloud.normals[0], Vec3f(-0.16884723f, -0.45159745f, -0.87609947f));
  EXPECT_EQ(cloud.curvature[0], 0.0030943851f);
  EXPECT_EQ(count_finite(cloud), 397u);
}

TEST(PcdSharedData, TableSceneBinaryCompressedOrganised) {
  const std::string path = test::shared_data("pcl/table_scene_mug_stereo_textured.pcd");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  const PointCloud cloud = read_pcd(path);
  EXPECT_EQ(cloud.width, 640u);
  EXPECT_EQ(cloud.height, 480u);
  ASSERT_EQ(cloud.size(), 640u * 480u);
  EXPECT_TRUE(cloud.organized());
  ASSERT_TRUE(cloud.has_rgba());
  EXPECT_FALSE(cloud.has_normals() || cloud.has_labels());
  EXPECT_TRUE(cloud.fields.empty());
  EXPECT_EQ(cloud.viewpoint.origin, Vec3f::Zero());
  // VIEWPOINT 0 0 0 0 1 0 0: qw = 0, qx = 1.
  EXPECT_EQ(cloud.viewpoint.orientation.w(), 0.0f);
  EXPECT_EQ(cloud.viewpoint.orientation.x(), 1.0f);
  const std::size_t finite = count_finite(cloud);
  EXPECT_GT(finite, 100000u);
  EXPECT_LT(finite, cloud.size());  // a stereo scan has holes, kept as NaN pixels
  // Valid points are in front of a camera a metre or so away.
  for (const Vec3f& p : cloud.xyz) {
    if (!is_finite(p)) continue;
    ASSERT_TRUE(p.z() > 0.1f && p.z() < 10.0f) << p.transpose();
  }
}

TEST(PcdSharedData, MosdLabelsZeroExactlyOnInvalidPoints) {
  const std::string path = test::shared_data("mosd/learn0.pcd");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  const PointCloud cloud = read_pcd(path);
  EXPECT_EQ(cloud.width, 640u);
  EXPECT_EQ(cloud.height, 480u);
  ASSERT_EQ(cloud.size(), 307200u);
  ASSERT_TRUE(cloud.has_labels());
  ASSERT_TRUE(cloud.has_rgba());
  EXPECT_TRUE(cloud.fields.empty());
  std::size_t invalid = 0, table = 0, objects = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const std::uint32_t label = cloud.labels[i];
    ASSERT_EQ(label == 0, !is_finite(cloud.xyz[i])) << "point " << i << " label " << label;
    invalid += label == 0;
    table += label >= 1 && label <= 9;
    objects += label >= 20;
    ASSERT_TRUE(label == 0 || (label >= 1 && label <= 9) || label >= 20) << label;
  }
  const std::size_t finite = count_finite(cloud);
  EXPECT_EQ(finite + invalid, cloud.size());
  EXPECT_GT(finite, 170000u);
  EXPECT_LT(finite, 195000u);
  EXPECT_GT(table, 0u);
  EXPECT_GT(objects, 0u);
}

TEST(PcdSharedData, PclFileSurvivesOurRoundTrip) {
  const std::string path = test::shared_data("mosd/learn0.pcd");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  const PointCloud cloud = read_pcd(path);
  test::TempDir dir;
  for (PcdEncoding encoding : kEncodings) {
    const std::string copy = dir.file("copy.pcd");
    write_pcd(copy, cloud, encoding);
    expect_same_cloud(cloud, read_pcd(copy));
  }
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A cloud whose planes have what LZF meets in a frame: runs (NaN pixels, one label), short
// periods and values that do not repeat.
PointCloud frame_like_cloud(std::size_t points) {
  PointCloud cloud;
  cloud.resize_unorganized(points);
  cloud.labels.resize(points);
  for (std::size_t i = 0; i < points; ++i) {
    const bool hole = (i / 700) % 3 == 0;
    const float x = 0.001f * float(i % 640), y = 0.001f * float(i / 640);
    cloud.xyz[i] = hole ? Vec3f(kNaN, kNaN, kNaN) : Vec3f(x, y, 1.0f + 0.01f * std::sin(x * y));
    cloud.labels[i] = hole ? 0 : std::uint32_t(1 + (i / 97) % 5);
  }
  return cloud;
}

// CloudWriteOptions: planes compressed as independent LZF segments read back exactly as the one
// stream does, and the file depends on the segment size, not the threads.
TEST(PcdWrite, SegmentedCompressionReadsBackLikeOneStream) {
  const PointCloud cloud = frame_like_cloud(20000);
  test::TempDir dir;
  CloudWriteOptions options;
  options.lzf_segment_bytes = 1001;  // segments end inside values; the last one is short
  options.threads = 1;
  write_pcd(dir.file("serial.pcd"), cloud, PcdEncoding::kBinaryCompressed, {}, options);
  options.threads = 3;
  write_pcd(dir.file("parallel.pcd"), cloud, PcdEncoding::kBinaryCompressed, {}, options);

  expect_same_cloud(cloud, read_pcd(dir.file("serial.pcd")));
  EXPECT_EQ(file_bytes(dir.file("serial.pcd")), file_bytes(dir.file("parallel.pcd")));
}

// Only a segment's first 8 KiB can lose references (LZF reaches no further back), so 1 MiB
// segments cost a frame under 1% in size.
TEST(PcdWrite, LargeSegmentsCompressNearlyAsWellAsOneStream) {
  const PointCloud cloud = frame_like_cloud(640 * 480);
  test::TempDir dir;
  write_pcd(dir.file("one.pcd"), cloud);
  CloudWriteOptions options;
  options.lzf_segment_bytes = 1 << 20;  // as the labeling clients write
  write_pcd(dir.file("segments.pcd"), cloud, PcdEncoding::kBinaryCompressed, {}, options);
  const std::size_t one = file_bytes(dir.file("one.pcd")).size();
  EXPECT_LE(file_bytes(dir.file("segments.pcd")).size(), one + one / 100);
}

TEST(PcdWrite, WithoutSegmentsTheFileIsTheOneStream) {
  const PointCloud cloud = frame_like_cloud(5000);
  test::TempDir dir;
  write_pcd(dir.file("default.pcd"), cloud);
  CloudWriteOptions options;
  options.lzf_segment_bytes = 1 << 20;  // larger than the planes: one segment
  write_pcd(dir.file("large_segments.pcd"), cloud, PcdEncoding::kBinaryCompressed, {}, options);
  EXPECT_EQ(file_bytes(dir.file("default.pcd")), file_bytes(dir.file("large_segments.pcd")));
}

TEST(PcdSharedData, AFrameInSegmentsReadsBackExactly) {
  const std::string path = test::shared_data("mosd/learn0.pcd");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  const PointCloud cloud = read_pcd(path);
  test::TempDir dir;
  CloudWriteOptions options;
  options.lzf_segment_bytes = 1 << 20;
  write_pcd(dir.file("segments.pcd"), cloud, PcdEncoding::kBinaryCompressed, {}, options);
  expect_same_cloud(cloud, read_pcd(dir.file("segments.pcd")));
}

// ---------------------------------------------------------------------------------------------
// Layouts and types

// Fields in an unusual order, with padding, in all three encodings.
class PcdFieldOrder : public ::testing::TestWithParam<PcdEncoding> {};

TEST_P(PcdFieldOrder, AnyOrderWithPaddingMapsByName) {
  test::TempDir dir;
  const std::string path = dir.file("order.pcd");
  const std::uint32_t rgb[2] = {0xff0a0b0cu, 0x00fffefdu};
  const float z[2] = {3.5f, kNaN};
  const std::uint16_t label[2] = {7, 65535};
  const float y[2] = {-2.25f, 1e-3f};
  const double x[2] = {0.1, -1e300};
  // Padding ("_") both between fields and at the end.
  const std::string fields = "rgb z _ label y x _";
  const std::string sizes = "4 4 4 2 4 8 1";
  const std::string types = "U F U U F F U";
  const std::string counts = "1 1 2 1 1 1 3";
  std::string file;
  if (GetParam() == PcdEncoding::kAscii) {
    file = header(fields, sizes, types, counts, 2, "ascii");
    file += "4278848268 3.5 99 98 7 -2.25 0.1 1 2 3\n";
    file += "16776957 nan 0 0 65535 0.001 -1e300 4 5 6\n";
  } else if (GetParam() == PcdEncoding::kBinary) {
    file = header(fields, sizes, types, counts, 2, "binary");
    for (int i = 0; i < 2; ++i) {
      put(file, rgb[i]);
      put(file, z[i]);
      put<std::uint64_t>(file, 0xdeadbeefdeadbeefull);  // padding
      put(file, label[i]);
      put(file, y[i]);
      put(file, x[i]);
      file += "pad";
    }
  } else {
    // binary_compressed planes leave out "_" fields, as PCL writes them.
    file = header(fields, sizes, types, counts, 2, "binary_compressed");
    std::string planes;
    for (int i = 0; i < 2; ++i) put(planes, rgb[i]);
    for (int i = 0; i < 2; ++i) put(planes, z[i]);
    for (int i = 0; i < 2; ++i) put(planes, label[i]);
    for (int i = 0; i < 2; ++i) put(planes, y[i]);
    for (int i = 0; i < 2; ++i) put(planes, x[i]);
    file += compressed_payload(planes);
  }
  write_bytes(path, file);

  const PointCloud cloud = read_pcd(path);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.xyz[0], Vec3f(0.1f, -2.25f, 3.5f));
  EXPECT_EQ(cloud.xyz[1].x(), -kInf);  // a double beyond float range saturates
  EXPECT_EQ(cloud.xyz[1].y(), 1e-3f);
  EXPECT_TRUE(std::isnan(cloud.xyz[1].z()));
  EXPECT_EQ(cloud.labels, (std::vector<std::uint32_t>{7, 65535}));
  EXPECT_EQ(cloud.rgba, (std::vector<std::uint32_t>{rgb[0], rgb[1]}));
  EXPECT_TRUE(cloud.fields.empty()) << "padding must not become a field";
}

INSTANTIATE_TEST_SUITE_P(AllEncodings, PcdFieldOrder, ::testing::ValuesIn(kEncodings),
                         encoding_name);

TEST(PcdRead, IntegerTypesOfEverySizeAndMultiValueFields) {
  test::TempDir dir;
  const std::string path = dir.file("types.pcd");
  const std::string fields = "x y z a b c d e f hist label";
  const std::string sizes = "4 4 4 1 1 2 2 8 8 4 1";
  const std::string types = "F F F I U I U I U F I";
  const std::string counts = "1 1 1 1 1 1 1 1 1 3 1";
  std::string ascii = header(fields, sizes, types, counts, 1, "ascii");
  ascii += "1 2 3 -128 255 -32768 65535 -1099511627776 1099511627776 0.5 nan -inf 100\n";
  write_bytes(path, ascii);
  const PointCloud from_ascii = read_pcd(path);

  std::string binary = header(fields, sizes, types, counts, 1, "binary");
  for (float v : {1.0f, 2.0f, 3.0f}) put(binary, v);
  put<std::int8_t>(binary, -128);
  put<std::uint8_t>(binary, 255);
  put<std::int16_t>(binary, -32768);
  put<std::uint16_t>(binary, 65535);
  put<std::int64_t>(binary, -1099511627776);
  put<std::uint64_t>(binary, 1099511627776);
  for (float v : {0.5f, kNaN, -kInf}) put(binary, v);
  put<std::int8_t>(binary, 100);
  write_bytes(path, binary);
  const PointCloud from_binary = read_pcd(path);

  for (const PointCloud* cloud : {&from_ascii, &from_binary}) {
    ASSERT_EQ(cloud->size(), 1u);
    EXPECT_EQ(cloud->xyz[0], Vec3f(1, 2, 3));
    EXPECT_EQ(cloud->labels, std::vector<std::uint32_t>{100});
    ASSERT_EQ(cloud->fields.size(), 7u);
    const float expected[] = {-128.0f,           255.0f,          -32768.0f, 65535.0f,
                              -1099511627776.0f, 1099511627776.0f};
    for (int f = 0; f < 6; ++f) {
      EXPECT_EQ(cloud->fields[f].count, 1);
      EXPECT_EQ(cloud->fields[f].values[0], expected[f]) << cloud->fields[f].name;
    }
    const FloatField* hist = cloud->find_field("hist");
    ASSERT_NE(hist, nullptr);
    EXPECT_EQ(hist->count, 3);
    EXPECT_EQ(hist->values[0], 0.5f);
    EXPECT_TRUE(std::isnan(hist->values[1]));
    EXPECT_EQ(hist->values[2], -kInf);
  }
}

TEST(PcdRead, FloatLabelsAndRgbTypedF) {
  test::TempDir dir;
  const std::string path = dir.file("flabel.pcd");
  std::string file = header("x y z label rgb", "4 4 4 4 4", "F F F F F", "1 1 1 1 1", 1, "binary");
  for (float v : {1.0f, 2.0f, 3.0f, 42.0f}) put(file, v);
  put<std::uint32_t>(file, 0x7fc0ffeeu);  // a packed colour whose float reading is a NaN
  write_bytes(path, file);
  const PointCloud cloud = read_pcd(path);
  EXPECT_EQ(cloud.labels, std::vector<std::uint32_t>{42});
  EXPECT_EQ(cloud.rgba, std::vector<std::uint32_t>{0x7fc0ffeeu});
}

TEST(PcdRead, OldHeaderWithoutCountOrViewpoint) {
  test::TempDir dir;
  const std::string path = dir.file("old.pcd");
  write_bytes(path,
              "# .PCD v.6\nVERSION .6\r\nFIELDS x y z\r\nSIZE 4 4 4\r\nTYPE F F F\r\n"
              "WIDTH 2\r\nHEIGHT 1\r\nPOINTS 2\r\nDATA ascii\r\n1 2 3\r\n\r\n4 5 6\r\n");
  const PointCloud cloud = read_pcd(path);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.xyz[1], Vec3f(4, 5, 6));
  EXPECT_TRUE(cloud.viewpoint.orientation.coeffs() == Eigen::Quaternionf::Identity().coeffs());
}

// A zero-area shape (found by fuzz_pcd_reader: WIDTH 3 HEIGHT 0 and no POINTS line) is an empty
// cloud whose width x height still equals its size.
TEST(PcdRead, ZeroAreaShapesAreOneEmptyRow) {
  test::TempDir dir;
  for (const std::string shape :
       {"WIDTH 3\nHEIGHT 0\n", "WIDTH 0\nHEIGHT 5\n", "WIDTH 3\nHEIGHT 0\nPOINTS 0\n"}) {
    for (const std::string data : {"ascii", "binary", "binary_compressed"}) {
      SCOPED_TRACE(shape + data);
      const std::string path = dir.file("empty.pcd");
      write_bytes(path, "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n" + shape + "DATA " +
                            data + "\n");
      const PointCloud cloud = read_pcd(path);
      EXPECT_EQ(cloud.size(), 0u);
      EXPECT_EQ(std::size_t{cloud.width} * cloud.height, cloud.size());
      EXPECT_EQ(cloud.height, 1u);
    }
  }
}

TEST(PcdRead, PartialNormalsBecomeOrdinaryFields) {
  test::TempDir dir;
  const std::string path = dir.file("partial.pcd");
  write_bytes(path,
              ascii_header("x y z normal_x", "4 4 4 4", "F F F F", "1 1 1 1") + "1 2 3 0.5\n");
  const PointCloud cloud = read_pcd(path);
  EXPECT_FALSE(cloud.has_normals());
  ASSERT_NE(cloud.find_field("normal_x"), nullptr);
  EXPECT_EQ(cloud.find_field("normal_x")->values[0], 0.5f);
}

TEST(CloudIo, DispatchesOnExtensionCaseInsensitively) {
  test::TempDir dir;
  const PointCloud cloud = awkward_cloud();
  write_cloud(dir.file("a.PCD"), cloud);
  expect_same_cloud(cloud, read_cloud(dir.file("a.PCD")));
  write_cloud(dir.file("b.Ply"), cloud);
  const PointCloud from_ply = read_cloud(dir.file("b.Ply"));
  EXPECT_EQ(from_ply.height, 1u);
  expect_same_attributes(cloud, from_ply);
  EXPECT_THROW(write_cloud(dir.file("c.xyz"), cloud), IoError);
  try {
    read_cloud(dir.file("noext"));
    ADD_FAILURE();
  } catch (const IoError& error) {
    EXPECT_NE(std::string(error.what()).find("unknown point cloud format"), std::string::npos);
  }
}

// ---------------------------------------------------------------------------------------------
// Malformed input

std::vector<MalformedFile> malformed_cases() {
  const std::string v7 = "# .PCD v0.7\nVERSION 0.7\n";
  std::string three_planes;
  for (int i = 0; i < 9; ++i) put(three_planes, static_cast<float>(i));
  std::string bad_lzf;  // a back-reference before the start of the output
  put<std::uint32_t>(bad_lzf, 3);
  put<std::uint32_t>(bad_lzf, 36);
  bad_lzf += std::string("\xe0\x10\x40", 3);
  std::string overlong_lzf;  // valid literals, but more of them than declared
  const std::string literals = lzf_literals(three_planes + three_planes);
  put<std::uint32_t>(overlong_lzf, static_cast<std::uint32_t>(literals.size()));
  put<std::uint32_t>(overlong_lzf, 36);
  overlong_lzf += literals;
  std::string big_compressed_size;
  put<std::uint32_t>(big_compressed_size, 1000);
  put<std::uint32_t>(big_compressed_size, 36);
  big_compressed_size += "abc";
  std::string wrong_uncompressed;
  put<std::uint32_t>(wrong_uncompressed, 10);
  put<std::uint32_t>(wrong_uncompressed, 40);
  wrong_uncompressed += std::string(10, '\0');

  return {
      {"SizeEntries",
       v7 + "FIELDS x y z w rgb\nSIZE 4 4 4 4\nTYPE F F F F F\nCOUNT 1 1 1 1 1\n"
            "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 4 5\n",
       "header line 4: SIZE has 4 entries but FIELDS has 5"},
      {"TypeEntries", v7 + "FIELDS x y z\nSIZE 4 4 4\nTYPE F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n",
       "header line 5: TYPE has 2 entries but FIELDS has 3"},
      {"CountEntries", v7 + "FIELDS x y z\nCOUNT 1\nPOINTS 1\nDATA ascii\n",
       "COUNT has 1 entries but FIELDS has 3"},
      {"FloatOfSizeTwo", ascii_header("x y z", "4 2 4", "F F F", "1 1 1") + "1 2 3\n",
       "field 'y' has TYPE F with SIZE 2 (F needs SIZE 4 or 8)"},
      {"SizeZero", ascii_header("x y z", "4 4 0", "F F F", "1 1 1"),
       "SIZE of field 'z' is '0', expected 1, 2, 4 or 8"},
      {"SizeNegative", ascii_header("x y z", "4 4 -4", "F F F", "1 1 1"),
       "SIZE of field 'z' is '-4'"},
      {"UnknownType", ascii_header("x y z", "4 4 4", "F D F", "1 1 1"),
       "TYPE of field 'y' is 'D', expected F, I or U"},
      {"CountZero", ascii_header("x y z", "4 4 4", "F F F", "1 0 1"),
       "COUNT of field 'y' is '0', expected a positive integer"},
      {"CountOnCoordinate", ascii_header("x y z", "4 4 4", "F F F", "1 1 2"),
       "field 'z' must have COUNT 1, got 2"},
      {"RgbOfSizeTwo", ascii_header("x y z rgb", "4 4 4 2", "F F F U", "1 1 1 1"),
       "field 'rgb' is a packed colour and needs SIZE 4"},
      {"DuplicateField", ascii_header("x y z y", "4 4 4 4", "F F F F", "1 1 1 1"),
       "field 'y' is listed twice"},
      {"MissingY", ascii_header("x z", "4 4", "F F", "1 1") + "1 2\n",
       "missing field 'y' (x, y and z are required)"},
      {"MissingFields", v7 + "WIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n", "missing FIELDS line"},
      {"UnknownDataKind", xyz_header(1, "binary_lzma") + "...", "unknown DATA kind 'binary_lzma'"},
      {"MissingDataLine",
       v7 + "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n"
            "POINTS 1\n",
       "missing DATA line"},
      {"DataWithoutDataLine",
       v7 + "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n"
            "POINTS 1\n1 2 3\n",
       "header line 9: data value '1' before any DATA line (missing DATA line?)"},
      {"UnknownKeyword", v7 + "FIELDS x y z\nCOLOUR red\nDATA ascii\n",
       "header line 4: unknown header keyword 'COLOUR'"},
      {"PlyFile", "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n",
       "header line 1: a PLY file, not a PCD file (read it with the PLY reader)"},
      {"UnsupportedVersion", "VERSION 2.0\nFIELDS x y z\nPOINTS 0\nDATA ascii\n",
       "header line 1: unsupported VERSION '2.0'"},
      {"DuplicateWidth", v7 + "FIELDS x y z\nWIDTH 1\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "header line 5: duplicate WIDTH line (first on line 4)"},
      {"WidthTimesHeight", v7 + "FIELDS x y z\nWIDTH 640\nHEIGHT 480\nPOINTS 1000\nDATA ascii\n",
       "WIDTH 640 x HEIGHT 480 = 307200 does not match POINTS 1000"},
      {"HeightZero", v7 + "FIELDS x y z\nWIDTH 3\nHEIGHT 0\nPOINTS 3\nDATA ascii\n",
       "WIDTH 3 x HEIGHT 0 = 0 does not match POINTS 3"},
      {"NegativeWidth", v7 + "FIELDS x y z\nWIDTH -3\nPOINTS 3\nDATA ascii\n",
       "header line 4: WIDTH must be a non-negative integer, got '-3'"},
      {"NonNumericPoints", v7 + "FIELDS x y z\nPOINTS many\nDATA ascii\n",
       "POINTS must be a non-negative integer, got 'many'"},
      {"WidthTooLarge", v7 + "FIELDS x y z\nWIDTH 5000000000\nPOINTS 5000000000\nDATA ascii\n",
       "WIDTH 5000000000 exceeds 4294967295"},
      {"ShortViewpoint", v7 + "FIELDS x y z\nVIEWPOINT 0 0 0 1\nPOINTS 0\nDATA ascii\n",
       "VIEWPOINT needs 7 values"},
      {"AsciiTooFewValues", xyz_header(2, "ascii") + "1 2 3\n4 5\n",
       "line 13: expected 3 values for point 1, found 2"},
      {"AsciiTooManyValues", xyz_header(1, "ascii") + "1 2 3 4\n",
       "line 12: expected 3 values for point 0, found 4"},
      {"AsciiNonNumeric", xyz_header(2, "ascii") + "1 2 3\n4 abc 6\n",
       "line 13: value 'abc' of field 'y' is not a valid F 4 number"},
      {"AsciiTrailingGarbage", xyz_header(1, "ascii") + "1 2 3x\n",
       "value '3x' of field 'z' is not a valid F 4 number"},
      {"AsciiIntegerOutOfRange", ascii_with_label("1", "U", 1, "1 2 3 256\n"),
       "value '256' of field 'label' is not a valid U 1 number"},
      {"AsciiNegativeUnsigned", ascii_with_label("4", "U", 1, "1 2 3 -1\n"),
       "value '-1' of field 'label' is not a valid U 4 number"},
      {"AsciiTooFewLines", xyz_header(3, "ascii") + "1 2 3\n4 5 6\n\n",
       "ascii data ends after 2 points, POINTS declares 3"},
      {"AsciiTooManyLines", xyz_header(1, "ascii") + "1 2 3\n4 5 6\n",
       "line 13: more data lines than POINTS (1)"},
      {"NegativeLabel", ascii_with_label("4", "I", 2, "1 2 3 5\n1 2 3 -1\n"),
       "field 'label' of point 1: value -1 is not a label"},
      {"FractionalLabel", ascii_with_label("4", "F", 1, "1 2 3 1.5\n"), "value 1.5 is not a label"},
      {"TruncatedBinary", xyz_header(3, "binary") + test::xyz_floats(1) + "abcdefgh",
       "truncated binary data: expected 36 bytes for 3 points, found 20"},
      {"HugePointsBinary",
       header("x y z", "4 4 4", "F F F", "1 1 1", 4000000000ull, "binary") + std::string(100, 'x'),
       "truncated binary data: expected 48000000000 bytes for 4000000000 points, found 100"},
      {"CompressedMissingSizes", xyz_header(3, "binary_compressed") + "abc",
       "truncated binary_compressed data: expected an 8-byte size header, found 3 bytes"},
      {"CompressedSizeBeyondFile", xyz_header(3, "binary_compressed") + big_compressed_size,
       "compressed size 1000 is larger than the 3 bytes remaining in the file"},
      {"UncompressedSizeMismatch", xyz_header(3, "binary_compressed") + wrong_uncompressed,
       "binary_compressed header says 40 uncompressed bytes, but 3 points x 12 bytes need 36"},
      {"CorruptLzf", xyz_header(3, "binary_compressed") + bad_lzf, "LZF decompression failed"},
      {"OverlongLzf", xyz_header(3, "binary_compressed") + overlong_lzf,
       "LZF decompression failed"},
      {"EmptyFile", "", "empty file, not a PCD file"},
  };
}

class PcdMalformed : public ::testing::TestWithParam<MalformedFile> {};

TEST_P(PcdMalformed, ThrowsIoErrorNamingFileAndProblem) {
  test::expect_rejected(read_pcd, GetParam(), ".pcd");
}

INSTANTIATE_TEST_SUITE_P(Cases, PcdMalformed, ::testing::ValuesIn(malformed_cases()),
                         test::malformed_file_name);

TEST(PcdMalformedFiles, MissingFileReportsErrno) {
  test::TempDir dir;
  expect_read_error(dir.file("nope.pcd"), "cannot open: No such file or directory");
}

TEST(PcdMalformedFiles, DirectoryIsNotARegularFile) {
  test::TempDir dir;
  const std::string path = dir.file("folder.pcd");
  std::filesystem::create_directory(path);
  expect_read_error(path, "not a regular file");
}

// Absurd sizes in tiny files must fail on the size check, before allocating anything like them.
class PcdHugeHeader : public ::testing::TestWithParam<MalformedFile> {};

TEST_P(PcdHugeHeader, FailsWithoutAllocatingTheDeclaredSize) {
  test::expect_rejected_without_allocating(read_pcd, GetParam(), ".pcd");
}

std::vector<MalformedFile> huge_cases() {
  const std::string huge = "4000000000";
  std::string consistent_sizes;  // 300M points x 12 bytes fit the uint32 size field
  put<std::uint32_t>(consistent_sizes, 4);
  put<std::uint32_t>(consistent_sizes, 3600000000u);
  consistent_sizes += "\x03xyzw";
  std::string tiny_sizes;
  put<std::uint32_t>(tiny_sizes, 4);
  put<std::uint32_t>(tiny_sizes, 4);
  tiny_sizes += "abcd";
  return {
      {"Binary", xyz_header(4000000000ull, "binary") + std::string(100, 'x'),
       "truncated binary data"},
      {"BinaryOverflowingProduct",
       header("x y z h", "4 4 4 8", "F F F F", "1 1 1 4000000000", 4000000000ull, "binary") +
           std::string(100, 'x'),
       "truncated binary data"},
      {"CompressedSizeMismatch", xyz_header(4000000000ull, "binary_compressed") + tiny_sizes,
       "binary_compressed header says 4 uncompressed bytes"},
      {"CompressedImpossibleRatio", xyz_header(300000000, "binary_compressed") + consistent_sizes,
       "LZF data of 4 bytes cannot expand to 3600000000 bytes"},
      {"Ascii", xyz_header(4000000000ull, "ascii") + "1 2 3\n4 5 6\n",
       "ascii data ends after 2 points, POINTS declares 4000000000"},
      {"AsciiHugeCount",
       ascii_header("x y z h", "4 4 4 4", "F F F F", "1 1 1 4000000000") + "1 2 3 4\n",
       "expected 4000000003 values for point 0, found 4"},
  };
}

INSTANTIATE_TEST_SUITE_P(Cases, PcdHugeHeader, ::testing::ValuesIn(huge_cases()),
                         test::malformed_file_name);

}  // namespace
}  // namespace primlabel
