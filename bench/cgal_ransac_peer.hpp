#pragma once
// The CGAL peer of primitive fitting: CGAL's Efficient RANSAC shape detection (Schnabel et al.
// 2007; CGAL/Shape_detection/Efficient_RANSAC.h) of planes, cylinders, spheres and tori on a
// cloud with normals, its shapes converted to primlabel's Primitive so both are scored alike
// (primitive_matching.hpp). CGAL detects on the whole cloud without labels, single-threaded.
// Built only where libcgal-dev is found (bench/CMakeLists.txt).

#include <cstdint>
#include <span>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/primitives/fit_primitives.hpp"

namespace primlabel::bench {

// Efficient RANSAC's parameters (CGAL's Parameters, same names). The defaults are primlabel's fit
// settings where both have one, so the comparison is about detection: epsilon = the 3 mm inlier
// band (FitSettings::distance_threshold, 6 sigma of the LMS400's 0.5 mm range noise and under the
// thinnest mug wall, 4 mm), normal_threshold = cos 30 degrees (FitSettings::normal_angle_deg),
// min_points = 50 (the benchmark's smallest scored true surface). cluster_epsilon, the largest
// gap inside one connected shape, is tied to the scan: see for_spacing.
struct CgalRansacParameters {
  double epsilon = 0.003;
  double normal_threshold = 0.866;  // cos(30 degrees)
  double cluster_epsilon = 0.008;
  std::size_t min_points = 50;
  double probability = 0.01;  // CGAL's default: chance of missing the largest shape
  std::uint64_t seed = 1;     // CGAL's default random generator, reseeded per call
  // CGAL's curved shapes contain simpler ones as their limits, and they often win there: a can's
  // wall comes back as a torus of major radius in kilometres, the table top as a cylinder of
  // 30 m. A shape whose (major) radius exceeds this bound (primlabel's own, FitSettings::
  // max_radius, far beyond any table-top object) is reported as what it degenerates to near its
  // points: such a torus as the cylinder around its centre circle's tangent (the minor radius as
  // radius), such a cylinder or sphere as the tangent plane. 0: report CGAL's shapes as they are.
  double degenerate_radius = 2.0;

  // cluster_epsilon = 4x the median point spacing (as primlabel's segments connect points within
  // 4x the spacing, docs/tools.md: Primitive instances); the rest as above.
  static CgalRansacParameters for_spacing(double point_spacing);
};

struct CgalDetections {
  // primitives sorted by points (most first), class_id from the model kind (cylinders, spheres,
  // tori convex or concave by their normals); inliers = points (CGAL assigns each point to at
  // most one shape), rms to the model, confidence 1; point_segment per input point.
  primitives::PrimitiveSet set;
  double seconds = 0;          // CGAL's detect() alone (wall time, one thread)
  std::size_t degenerate = 0;  // shapes reported as their limit (see degenerate_radius)
};

// What a CGAL shape of (major) radius over `limit` is near its points (xyz[points]): a cylinder
// or sphere the plane tangent where the direction from its axis or centre through the points'
// centroid meets it, a torus the cylinder (minor radius) around its centre circle's tangent
// there. Other models, and any model when limit <= 0, come back unchanged.
primitives::Model degenerate_limit(const primitives::Model& model, const std::vector<Vec3f>& xyz,
                                   std::span<const std::uint32_t> points, double limit);

// `normals` holds one normal per point. Points or normals that are not finite take no part.
// Throws std::invalid_argument when the sizes differ.
CgalDetections detect_with_cgal(const std::vector<Vec3f>& xyz, std::span<const Vec3f> normals,
                                const CgalRansacParameters& parameters);

}  // namespace primlabel::bench
