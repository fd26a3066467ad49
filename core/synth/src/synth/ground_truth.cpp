#include "primlabel/synth/ground_truth.hpp"

namespace primlabel::synth {

PrimitiveClass ground_truth(const Scene& scene, int object, int part, const Vec3d& p,
                            double radius) {
  const SceneObject& owner = scene.objects[object];
  const Shape& shape = *owner.shape;
  const Vec3d local = owner.local_from_world * p;

  int edges = 0;
  bool rim = false;
  PrimitiveClass edge_class = PrimitiveClass::kEdgeConvex;
  auto add_edge = [&](PrimitiveClass c) {
    ++edges;
    edge_class = c;
  };

  for (const Feature& feature : shape.features()) {
    if (!(feature.parts >> part & 1u) || feature.distance(local) >= radius) continue;
    switch (feature.kind) {
      case Feature::Kind::kRim:
        rim = true;
        break;
      case Feature::Kind::kConvexEdge:
        add_edge(PrimitiveClass::kEdgeConvex);
        break;
      case Feature::Kind::kConcaveEdge:
        add_edge(PrimitiveClass::kEdgeConcave);
        break;
    }
  }

  if (owner.on_support) {
    // The exposed table top is the plane z = 0 outside the object's footprint.
    if (shape.exterior(part) && std::hypot(local.z(), shape.footprint_inset(local)) < radius)
      add_edge(PrimitiveClass::kEdgeConcave);
  } else {
    // A table point: one contact crease per object within reach.
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      const SceneObject& other = scene.objects[i];
      if (!other.on_support) continue;
      if ((p - other.bound_center).norm() - other.bound_radius >= radius) continue;
      if (other.shape->distance_outside(other.local_from_world * p) < radius)
        add_edge(PrimitiveClass::kEdgeConcave);
    }
  }

  if (edges >= 2) return PrimitiveClass::kCorner;
  if (rim) return PrimitiveClass::kTorusConvex;
  if (edges == 1) return edge_class;
  return shape.surface_class(part, local);
}

}  // namespace primlabel::synth
