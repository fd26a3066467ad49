// Format dispatch on the file extension.

#include "primlabel/geometry/cloud_io.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

#include "io_util.hpp"

namespace primlabel {
namespace {

enum class CloudFormat { kPcd, kPly };

CloudFormat format_of(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".pcd") return CloudFormat::kPcd;
  if (extension == ".ply") return CloudFormat::kPly;
  io_detail::throw_io_error(path, "unknown point cloud format " +
                                      (extension.empty() ? std::string("(no extension)")
                                                         : io_detail::in_quotes(extension)) +
                                      ", expected .pcd or .ply");
}

}  // namespace

PointCloud read_cloud(const std::string& path) {
  return format_of(path) == CloudFormat::kPcd ? read_pcd(path) : read_ply(path);
}

void write_cloud(const std::string& path, const PointCloud& cloud, const HeaderComments& comments,
                 const CloudWriteOptions& options) {
  if (format_of(path) == CloudFormat::kPcd)
    write_pcd(path, cloud, PcdEncoding::kBinaryCompressed, comments, options);
  else
    write_ply(path, cloud, PlyEncoding::kBinaryLittleEndian, comments);
}

}  // namespace primlabel
