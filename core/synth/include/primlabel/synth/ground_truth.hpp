#pragma once
// Ground-truth labels at a scale. A point's class is the primitive its surface forms within the
// label radius r - the descriptor's support radius - so the label says what a descriptor of that
// radius sees:
//   - within r of two or more edges (convex, concave or contact creases): corner;
//   - else within r of a rim (the lip of a mug, cup or bowl): torus-convex;
//   - else within r of one edge: that edge's class (edge-convex / edge-concave);
//   - else the class of the part it lies on (plane, cylinder-*, sphere-*, torus-*).
// Contact creases: where an object stands on the table the two surfaces meet in a concave
// crease, so an object's exterior point within r of the exposed table top, and a table point
// within r of an object, are edge-concave (the box's bottom edges, the foot of a can or bowl,
// the table around a ball). Features only act on the object they belong to (objects are placed
// farther apart than the usual label radius).

#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/synth/scene.hpp"

namespace primlabel::synth {

// The class of world point `p` on (object, part) at label radius `radius`.
PrimitiveClass ground_truth(const Scene& scene, int object, int part, const Vec3d& p,
                            double radius);

}  // namespace primlabel::synth
