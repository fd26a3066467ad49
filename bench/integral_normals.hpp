#pragma once
// Integral-image normals (Holzer et al. 2012, the covariance variant) on an organised depth
// frame: the sums of the points' coordinates and of their products over every pixel rectangle,
// read in O(1) from integral images, give a window's covariance and so its plane normal and
// surface variation. Used by `primlabel-bench organised` to carry them to the served model's voxel
// centroids (one depth-adaptive window per voxel) beside the served PCA normals; not used by the
// labeling path (docs/results.md, issue 48 item 1).

#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::bench {

class IntegralMoments {
 public:
  // Throws std::invalid_argument when `frame` is not organised. Non-finite pixels count nowhere.
  explicit IntegralMoments(const PointCloud& frame);

  // The normal (facing `viewpoint`) and surface variation of the finite pixels of columns
  // [u0, u1] x rows [v0, v1], clipped to the image; false when fewer than 3 or no spread.
  bool normal(int u0, int v0, int u1, int v1, const Vec3f& viewpoint, Vec3f& normal,
              float& variation) const;

 private:
  static constexpr int kMoments = 10;  // count, x, y, z, xx, xy, xz, yy, yz, zz
  const double* at(int u, int v) const {
    return sums_.data() + (std::size_t(v) * std::size_t(width_ + 1) + std::size_t(u)) * kMoments;
  }
  int width_ = 0, height_ = 0;
  Vec3f centre_ = Vec3f::Zero();  // subtracted before summing: smaller sums, less cancellation
  std::vector<double> sums_;      // (height + 1) x (width + 1) x kMoments, a zero row and column
};

// The focal length in pixels of a pinhole camera at the viewpoint that best explains the frame's
// pixel columns and rows (least squares of u against x/z and v against y/z); NaN with fewer than
// 16 finite pixels in front of it.
float estimate_focal(const PointCloud& frame);

struct VoxelNormals {
  std::vector<Vec3f> normals;    // NaN where the window had fewer than 3 points
  std::vector<float> variation;  // surface variation, NaN likewise
};

// Per voxel of `voxels` (built on `frame`'s pixel indices) its pixel: its members' rounded mean
// column and row, as a pixel index.
std::vector<std::uint32_t> voxel_pixels(const PointCloud& frame, const tabletop::VoxelGrid& voxels);

// Per voxel: the integral-image normal of the window of half-size round(radius * focal / d)
// pixels around its pixel, d the centroid's distance from the viewpoint (the window a sphere of
// that radius spans there).
VoxelNormals integral_voxel_normals(const PointCloud& frame, const IntegralMoments& moments,
                                    const tabletop::VoxelGrid& voxels,
                                    const std::vector<std::uint32_t>& pixels, float radius,
                                    float focal);

// Per pixel of `frame`: the normal of its own window of half-size round(radius * focal / d)
// (NaN for a miss or a window of fewer than 3 points), for a labeling with the cloud's own
// normals (LabelingOptions::use_cloud_normals carries their mean to each voxel).
std::vector<Vec3f> integral_pixel_normals(const PointCloud& frame, const IntegralMoments& moments,
                                          float radius, float focal);

}  // namespace primlabel::bench
