#pragma once
// Reading and writing point clouds: PCD v0.7 (ascii, binary, binary_compressed) and PLY (ascii,
// binary_little_endian). Errors are reported as IoError whose message names the file and says
// what is wrong with it.

#include <stdexcept>
#include <string>

#include "primlabel/core/point_cloud.hpp"

namespace primlabel {

class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class PcdEncoding { kAscii, kBinary, kBinaryCompressed };
enum class PlyEncoding { kAscii, kBinaryLittleEndian };

PointCloud read_pcd(const std::string& path);
void write_pcd(const std::string& path, const PointCloud& cloud,
               PcdEncoding encoding = PcdEncoding::kBinaryCompressed);

PointCloud read_ply(const std::string& path);
void write_ply(const std::string& path, const PointCloud& cloud,
               PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian);

// Dispatch on the extension (.pcd / .ply, case-insensitive); anything else is an IoError.
PointCloud read_cloud(const std::string& path);
void write_cloud(const std::string& path, const PointCloud& cloud);

}  // namespace primlabel
