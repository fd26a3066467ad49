#pragma once
// Reading and writing point clouds: PCD v0.7 (ascii, binary, binary_compressed) and PLY (ascii,
// binary_little_endian; binary_big_endian is read too). Errors are reported as IoError whose
// message starts with the file path and says what is wrong with it. Writes are atomic and durable
// (atomic_write_file: a temporary file beside the target, fsynced, renamed over it, directory
// fsynced).
//
// Field mapping (PCD field / PLY vertex property -> PointCloud):
//   x y z -> xyz (required); normal_x normal_y normal_z (PLY: nx ny nz) -> normals;
//   curvature -> curvature; label -> labels (must be integers in 0..2^32-1);
//   PCD rgb/rgba (4 bytes, bit pattern kept) or PLY red green blue [alpha] uchar -> rgba;
//   anything else -> a FloatField (PCD keeps COUNT; PLY name_0..name_k runs form one field).
// Writing a multi-value field (fpfh, 33 values): PCD as one field with its COUNT (PCL's form)
// and also as scalar columns name_0..name_k (Open3D reads one value per field), which reading
// folds back into the field; PLY as the scalar columns only.
//   PCD "_" padding fields are skipped. PLY clouds are read as one row (height 1).

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel {

class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class PcdEncoding { kAscii, kBinary, kBinaryCompressed };
enum class PlyEncoding { kAscii, kBinaryLittleEndian };

// Header comment lines a writer puts right after the format's first line (PCD: after
// "# .PCD v0.7 ...", as "# <line>"; PLY: after "format ...", as "comment <line>"). Readers
// (ours, PCL's, Open3D's) skip them. A line holding '\r' or '\n' is an std::invalid_argument.
using HeaderComments = std::vector<std::string>;

// How DATA binary_compressed is compressed. By default as one LZF stream over every field's
// plane, as PCL writes it. With lzf_segment_bytes > 0 each plane is cut into segments of at most
// that many bytes (whole values), each compressed as an LZF stream of its own on `threads`
// threads (0: OpenMP's default), straight from the cloud's arrays where its values lie one after
// another, and concatenated in order: still one valid LZF stream, which every reader (ours,
// PCL's) decodes to the same planes; only a segment's first 8 KiB can lose references (LZF
// reaches no further back), under 1% of a frame's size with 1 MiB segments. The bytes written
// depend on the segment size, never on the thread count. For writers on a latency path (the
// labeling clients): a 640x480 frame's 7 MB of planes take ~13 ms to compress as one stream.
struct CloudWriteOptions {
  std::size_t lzf_segment_bytes = 0;
  int threads = 0;
};

PointCloud read_pcd(const std::string& path);
void write_pcd(const std::string& path, const PointCloud& cloud,
               PcdEncoding encoding = PcdEncoding::kBinaryCompressed,
               const HeaderComments& comments = {}, const CloudWriteOptions& options = {});

PointCloud read_ply(const std::string& path);
void write_ply(const std::string& path, const PointCloud& cloud,
               PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian,
               const HeaderComments& comments = {});

// Dispatch on the extension (.pcd / .ply, case-insensitive); anything else is an IoError.
PointCloud read_cloud(const std::string& path);
void write_cloud(const std::string& path, const PointCloud& cloud,
                 const HeaderComments& comments = {}, const CloudWriteOptions& options = {});

}  // namespace primlabel
