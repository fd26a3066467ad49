#pragma once
// A radius search over the sensor's image plane, for points seen from one viewpoint (a depth
// frame, or the voxel centroids of one): every point is filed under the bucket of its projection
// (x/z, y/z in the sensor's frame, i.e. its pixel up to the focal length), and a query reads only
// the buckets inside the projection of its sphere (exact: the sphere's tangent planes through the
// viewpoint), row by row over the ellipse's span in that row. Candidates are kept strictly within
// the radius with the radius grid's float distance, so the set is the one NeighborSearch returns;
// the order is bucket order, not the radius grid's.
//
// The organised-frame path of issue 48 measured against the radius grid (`primlabel-bench
// organised`); not used by the labeling path (docs/results.md, issue 48 item 1).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::bench {

class ImageGrid {
 public:
  // Buckets sized for queries of `radius` (half a sphere's window at the median depth). Non-finite
  // points are left out (never neighbours). nullptr when there is no finite point, the radius is
  // not positive and finite, or a finite point lies on or behind the viewpoint's image plane (it
  // has no projection). `points` may change or go once this returns (the grid keeps a copy).
  static std::unique_ptr<ImageGrid> build(const std::vector<Vec3f>& points, float radius,
                                          const Viewpoint& viewpoint);

  // Appends the points strictly within `radius` of q (indices into the built vector and squared
  // distances). A non-finite q has none. False, with nothing appended, when the sphere reaches
  // the viewpoint's image plane (its projection is unbounded): the caller searches otherwise.
  // `candidates` (optional) gets how many points were compared. Thread-safe.
  bool find(const Vec3f& q, float radius, NeighborList& out,
            std::size_t* candidates = nullptr) const;

  std::size_t indexed_points() const { return index_.size(); }

 private:
  ImageGrid() = default;
  Vec3f to_sensor(const Vec3f& p) const;
  // The bucket column (or row) of an image coordinate, clamped to the grid.
  std::int64_t bucket(double v, double v0, std::int64_t count) const;

  Vec3f origin_ = Vec3f::Zero();
  Eigen::Matrix3f to_sensor_ = Eigen::Matrix3f::Identity();  // the viewpoint's inverse rotation
  bool identity_ = true;
  double s0_ = 0, t0_ = 0, inv_bucket_ = 1;
  std::int64_t cols_ = 1, rows_ = 1;
  std::vector<std::uint32_t> starts_;  // per bucket (row-major), into index_; one more at the end
  std::vector<std::uint32_t> index_;   // point index per slot
  std::vector<Vec3f> points_;          // per slot, as given (not in the sensor's frame)
};

}  // namespace primlabel::bench
