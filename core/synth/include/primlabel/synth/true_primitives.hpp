#pragma once
// The primitives a synthetic scene is made of, in the world frame: the ground truth for primitive
// fitting (primlabel-synth --primitives, primlabel-bench primitives). Box faces and caps are
// planes, can and mug walls cylinders, balls and bowls spheres, rings tori. A mug's handle (a
// torus arc) and a bowl's lip are left out: no model of the taxonomy describes them whole.

#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/primitives/primitive.hpp"
#include "primlabel/synth/scene.hpp"

namespace primlabel::synth {

struct TruePrimitive {
  int object = 0;  // index into Scene::objects (0 the table)
  // class_id and model set; points = the scan points on it (see count_points_on), the rest 0;
  // confidence 1.
  primitives::Primitive primitive;
  // Of primitive.points, those nearer to this primitive than to any other of its object's that
  // the point's class counts for (ties: the first listed): a point along an edge two faces share
  // counts for one. A face the scan never sees keeps only the adjacent faces' points within the
  // tolerance of its edges in `points`, none here (see count_points_on).
  std::size_t own_points = 0;
};

std::vector<TruePrimitive> true_primitives(const Scene& scene);

// Distance (m) from p to the model's surface, within its extent: planes measure to their
// rectangle, cylinders to their finite wall; +inf for kSegment.
double distance_to(const primitives::Model& model, const Eigen::Vector3d& p);

// Sets each true primitive's `points` to the points of `cloud` (fields `object` and `label`) of
// its object and class (for tori either torus class) within `tolerance` of its surface; the same
// point may count for two faces along their shared edge. Sets own_points too.
void count_points_on(std::vector<TruePrimitive>& truth, const PointCloud& cloud, double tolerance);

}  // namespace primlabel::synth
