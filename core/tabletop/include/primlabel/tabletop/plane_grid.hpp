#pragma once
// Points near a plane binned into square cells of the plane's own 2D coordinates. Gives, in time
// linear in the points, (1) the pieces connected through occupied neighbouring cells (the table's
// connectivity: points in the band are effectively two-dimensional, so a 2D grid replaces a 3D
// neighbour search), (2) local surface normals from the points of 3x3 cells, which tell a real
// surface lying in the plane from a plane that merely slices through other surfaces (walls,
// object sides: their points in the band have normals along the plane), and (3) how many points
// lie under a polygon, to ask whether the table is seen inside an object's footprint.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/tabletop/convex_hull.hpp"

namespace primlabel::tabletop {

class PlaneGrid {
 public:
  // Bins points[indices] (finite; `points` must outlive the grid) by their projection on `plane`
  // (n.p + d = 0, |n| = 1) into cells of edge `cell` (m, > 0). Plane coordinates are (p.u, p.v)
  // with plane_basis(n, u, v).
  PlaneGrid(const std::vector<Vec3f>& points, const std::vector<std::uint32_t>& indices,
            const Eigen::Vector4f& plane, float cell);

  Vec2f project(const Vec3f& p) const { return Vec2f(p.dot(u_), p.dot(v_)); }
  std::size_t num_cells() const { return cells_.size(); }
  float cell() const { return cell_; }

  // Pieces of the points connected through occupied cells that share an edge or a corner; each
  // lists input indices ascending; largest first, ties by first index.
  std::vector<std::vector<std::uint32_t>> connected_parts() const;

  // Fraction of points[subset] (all binned here) whose local surface, the least-squares plane
  // through the points of the 3x3 cells around theirs, is within max_angle_deg of the plane's.
  // Points whose 3x3 cells hold fewer than 6 points are not counted. 0 when none is counted.
  double fraction_parallel(const std::vector<std::uint32_t>& subset, float max_angle_deg) const;

  // The points of points[subset] (all binned here) that may be vertices of their convex hull in
  // plane coordinates, projected: all but those of cells enclosed by cells holding the subset.
  std::vector<Vec2f> hull_candidates(const std::vector<std::uint32_t>& subset) const;

  // Sorted keys of the cells (of this grid's layout) under points[indices], grown by `grow`
  // cells in every direction: an object's footprint. The points must lie near the binned ones.
  std::vector<std::uint64_t> footprint(const std::vector<Vec3f>& points,
                                       const std::vector<std::uint32_t>& indices, int grow) const;

  // Points in the cells whose centre lies inside the CCW polygon (plane coordinates) shrunk by
  // `margin` (m), except the cells in `excluded` (sorted keys, as footprint() gives).
  std::size_t count_inside(const std::vector<Vec2f>& polygon, float margin,
                           const std::vector<std::uint64_t>& excluded = {}) const;

 private:
  struct Cell {
    std::int32_t x, y;         // integer cell coordinates
    std::uint32_t count = 0;   // points binned here
    Eigen::Vector3d sum;       // of the points, relative to origin_
    Eigen::Matrix3d products;  // sum of outer products, relative to origin_
  };
  std::int64_t find(std::int32_t x, std::int32_t y) const;  // cell index or -1

  const std::vector<Vec3f>& points_;    // must outlive the grid
  std::vector<std::uint32_t> indices_;  // ascending
  Eigen::Vector3f normal_, u_, v_;
  Eigen::Vector3d origin_;  // the first point, for well-conditioned sums
  float cell_;
  std::vector<Cell> cells_;                   // in order of first appearance in indices_
  std::vector<std::uint32_t> cell_of_point_;  // per input point; UINT32_MAX when not binned
  std::vector<std::uint32_t> hash_;           // open addressing: cell index or UINT32_MAX
};

}  // namespace primlabel::tabletop
