#pragma once
// Helpers shared by the PCD and PLY tests (test_pcd_io, test_ply_io): raw file bytes, a cloud of
// awkward values compared bit for bit, and the checks that a malformed file is rejected.

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include "allocation_guard.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "test_util.hpp"

namespace primlabel::test {

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline constexpr float kInf = std::numeric_limits<float>::infinity();

// Appends the bytes of `value` as they are in memory (little-endian on every machine we test).
template <typename T>
void put(std::string& out, T value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof value);
}

// The floats 0, 1, 2, ... of `points` binary x y z points.
inline std::string xyz_floats(int points) {
  std::string out;
  for (int i = 0; i < 3 * points; ++i) put(out, static_cast<float>(i));
  return out;
}

// Bit for bit (so -0 differs from 0), except that any NaN matches any NaN.
inline bool same_float(float a, float b) {
  return (std::isnan(a) && std::isnan(b)) ||
         std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

inline void expect_same_floats(const std::vector<float>& a, const std::vector<float>& b,
                               const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i)
    ASSERT_TRUE(same_float(a[i], b[i])) << what << "[" << i << "]: " << a[i] << " vs " << b[i];
}

inline std::vector<float> flatten(const std::vector<Vec3f>& points) {
  std::vector<float> out;
  for (const Vec3f& p : points) out.insert(out.end(), {p.x(), p.y(), p.z()});
  return out;
}

// An organised 4x3 cloud with invalid (NaN) pixels and awkward float values in every attribute.
inline PointCloud awkward_cloud() {
  const float specials[] = {0.1f,          -0.0f, 1e-40f /* subnormal */,
                            3.4028235e38f, -kInf, 1.17549435e-38f,
                            123456.789f,   1e-7f, 3.14159265f};
  PointCloud cloud;
  cloud.width = 4;
  cloud.height = 3;
  for (int i = 0; i < 12; ++i) {
    const float s = specials[i % 9];
    const bool invalid = i == 1 || i == 6 || i == 11;
    cloud.xyz.push_back(invalid ? Vec3f(kNaN, kNaN, kNaN) : Vec3f(s, -s * 0.5f, 1.0f + i));
    cloud.normals.push_back(invalid ? Vec3f(kNaN, kNaN, kNaN) : Vec3f(0.6f, -0.8f, s));
    cloud.curvature.push_back(invalid ? kNaN : s);
    cloud.labels.push_back(i == 0 ? 0u : i == 5 ? 0xffffffffu : static_cast<std::uint32_t>(i * 7));
    cloud.rgba.push_back(i == 3 ? 0xffffffffu : 0xff102030u + static_cast<std::uint32_t>(i));
  }
  FloatField& fpfh = cloud.set_field("fpfh", 33);
  for (std::size_t v = 0; v < fpfh.values.size(); ++v)
    fpfh.values[v] = v % 17 == 0 ? kNaN : static_cast<float>(v) / 7.0f;
  FloatField& intensity = cloud.set_field("intensity", 1);
  for (std::size_t v = 0; v < intensity.values.size(); ++v) intensity.values[v] = specials[v % 9];
  cloud.viewpoint.origin = Vec3f(0.25f, -1.5f, 3.0f);
  cloud.viewpoint.orientation = Eigen::Quaternionf(0.5f, 0.5f, -0.5f, 0.5f);
  return cloud;
}

// Every per-point attribute and field, bit for bit (not the shape or the viewpoint).
inline void expect_same_attributes(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  expect_same_floats(flatten(a.xyz), flatten(b.xyz), "xyz");
  expect_same_floats(flatten(a.normals), flatten(b.normals), "normals");
  expect_same_floats(a.curvature, b.curvature, "curvature");
  EXPECT_EQ(a.labels, b.labels);
  EXPECT_EQ(a.rgba, b.rgba);
  ASSERT_EQ(a.fields.size(), b.fields.size());
  for (std::size_t f = 0; f < a.fields.size(); ++f) {
    EXPECT_EQ(a.fields[f].name, b.fields[f].name);
    EXPECT_EQ(a.fields[f].count, b.fields[f].count);
    expect_same_floats(a.fields[f].values, b.fields[f].values, a.fields[f].name);
  }
}

// read_pcd or read_ply.
using CloudReader = PointCloud (*)(const std::string& path);

// Asserts that read(path) throws an IoError that starts with the path and mentions `needle`.
inline void expect_read_error(CloudReader read, const std::string& path,
                              const std::string& needle) {
  try {
    read(path);
    ADD_FAILURE() << "no IoError for " << path << " (expected '" << needle << "')";
  } catch (const IoError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
    EXPECT_NE(message.find(needle), std::string::npos)
        << "message: " << message << "\nexpected to contain: " << needle;
  }
}

// A file the reader must reject, and what its error must say.
struct MalformedFile {
  const char* name;
  std::string contents;
  const char* expected;
};

// Names the case in gtest output instead of dumping its bytes.
inline void PrintTo(const MalformedFile& c, std::ostream* out) { *out << c.name; }

inline std::string malformed_file_name(const ::testing::TestParamInfo<MalformedFile>& info) {
  return info.param.name;
}

// Writes the case to <name><extension> in a fresh directory and expects `read` to reject it.
inline void expect_rejected(CloudReader read, const MalformedFile& c,
                            const std::string& extension) {
  TempDir dir;
  const std::string path = dir.file(c.name + extension);
  write_bytes(path, c.contents);
  expect_read_error(read, path, c.expected);
}

// As expect_rejected, for absurd sizes in a tiny file: the size check must fail before anything
// like them is allocated. Needs allocation_guard.cpp (whose own test is test_allocation_guard.cpp).
inline void expect_rejected_without_allocating(CloudReader read, const MalformedFile& c,
                                               const std::string& extension) {
  TempDir dir;
  const std::string path = dir.file(c.name + extension);
  write_bytes(path, c.contents);
  reset_largest_allocation();
  expect_read_error(read, path, c.expected);
  EXPECT_LT(largest_allocation(), std::size_t{1} << 20)
      << "largest allocation while reading a " << c.contents.size() << "-byte file";
}

}  // namespace primlabel::test
