#pragma once
// Instance matching of fitted primitives against a scene's true primitives, the same rule for
// every detector the primitives benchmark compares (primlabel from predicted or true labels,
// CGAL's Efficient RANSAC). A detection lies on a true primitive when at least half of its points
// are points of that primitive's object within `tolerance` of its surface (synth::distance_to);
// its true primitive is the one of the same model kind with most of its points, and it is a
// wrong instance (not matched) when its parameters are off that primitive's by more than the
// gates (5x the targets, so the error figures still show what is matched). Each true
// primitive is matched by at most one detection (the one with most points on it): a second
// detection of the same surface, a detection on no true surface and a detection of the wrong
// kind all count against precision. Recall is over the visible true primitives: those with at
// least `min_true_points` scan points of their class that are theirs (TruePrimitive::own_points:
// nearer to them than to another of their object's primitives). The listed count
// (primitive.points, which also takes the adjacent faces' points within the tolerance of an
// edge, so a face the scan never sees can reach it) is reported beside it.

#include <cstddef>
#include <span>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/primitives/fit_primitives.hpp"
#include "primlabel/synth/true_primitives.hpp"

namespace primlabel::bench {

struct MatchOptions {
  double tolerance = 0.003;  // m: a point is on a true surface within this distance
  std::size_t min_true_points = 50;
  // Detections with fewer points are not scored (neither side reports them as instances).
  std::size_t min_detection_points = 50;
  double max_angle_deg = 10;       // axis (cylinder, torus) or normal (plane) against the true one
  double max_radius_error = 0.01;  // m: cylinder, sphere radius; torus major radius
};

// A true primitive and the detection matched to it, with the errors of its parameters.
struct MatchedPair {
  std::size_t truth = 0, detection = 0;  // indices into the truth and the detections
  double radius_error = 0;               // |fitted - true| (m): cylinder, sphere, torus major
  double axis_error_deg = 0;             // cylinder, torus: angle between axes; plane: normals
};

struct InstanceMatch {
  std::size_t true_instances = 0;    // visible true primitives: own_points >= min_true_points
  std::size_t found = 0;             // of those, matched
  std::size_t listed_instances = 0;  // true primitives with primitive.points >= min_true_points
  std::size_t listed_found = 0;      // of those, matched
  std::size_t detections = 0;        // plane/cylinder/sphere/torus with >= min_detection_points
  std::size_t correct = 0;           // detections matched one to one to a true primitive
  std::vector<MatchedPair> pairs;    // every match (also of true primitives under the threshold)
};

// `object[i]` is point i's object index (the synthetic cloud's `object` field); `detected`'s
// point_segment gives each point's detection (primitives::kNoSegment: none).
// The rule a true primitive is scored by (recall's denominator).
bool visible(const synth::TruePrimitive& truth, const MatchOptions& options);

InstanceMatch match_instances(const primitives::PrimitiveSet& detected,
                              const std::vector<Vec3f>& xyz, std::span<const float> object,
                              const std::vector<synth::TruePrimitive>& truth,
                              const MatchOptions& options = {});

// The angle between two lines' directions (degrees, in [0, 90]).
double axis_angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

}  // namespace primlabel::bench
