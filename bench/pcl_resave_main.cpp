// Reads a PCD with PCL's own reader and saves what PCL understood as ASCII PCD: the proof that
// primlabel's labeled files (binary_compressed, header tags as comment lines) load in PCL
// (tests: interop.PclReadsLabeledPcd).

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: primlabel-pcl-resave IN.pcd OUT.pcd\n");
    return 2;
  }
  pcl::PointCloud<pcl::PointXYZL> cloud;
  if (pcl::io::loadPCDFile(argv[1], cloud) != 0) {
    std::fprintf(stderr, "primlabel-pcl-resave: PCL could not read %s\n", argv[1]);
    return 1;
  }
  if (pcl::io::savePCDFileASCII(argv[2], cloud) != 0) return 1;
  std::printf("%zu points (%u x %u)\n", cloud.size(), cloud.width, cloud.height);
  return 0;
}
