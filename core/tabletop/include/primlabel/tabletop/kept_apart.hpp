#pragma once
// Points a refinement step found to be other objects than each other (the shape split's pieces of
// one cluster), so that later steps do not join them again: the occlusion merge links a can to
// the box it stands in front of exactly as it links the two halves of one object.
//
// The shape split also hands on the balls and cans it fitted: their surfaces bound their solids
// all round, so what lies outside one is another object, whichever cluster it came in. Two balls
// in contact arrive in two clusters (the crease split cuts at their contact), which the merge
// would join again: they have one height and colour and no table between them. (A box's rounded
// edge fitted as a can is not handed on: see shape_split.hpp.)

#include <cstddef>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::tabletop {

struct KeptApart {
  std::vector<std::int32_t> piece;    // per input point: its piece, -1 outside cut clusters;
                                      // empty when nothing was cut
  std::vector<std::uint32_t> origin;  // per piece: the cluster it was cut from

  // An object-sized can's or ball's solid the shape split fitted, and what counts as outside it.
  struct Solid {
    Vec3f centre = Vec3f::Zero();  // a ball's centre; a point on a can's axis
    Vec3f axis = Vec3f::UnitZ();   // a can's
    float radius = 0;
    bool ball = false;
    float band = 0;            // outside: farther than this beyond the surface (m)
    float share = 0.5f;        // of a cluster's points outside: another object
    std::uint32_t anchor = 0;  // an input point of its surface: the cluster holding it is its own

    // Signed distance outside the solid (> 0: in front of its surface).
    float in_front(const Vec3f& p) const {
      const Vec3f q = p - centre;
      return (ball ? q : Vec3f(q - q.dot(axis) * axis)).norm() - radius;
    }
  };
  std::vector<Solid> solids;

  // Whether points i and j lie in different pieces of one cluster.
  bool apart(std::uint32_t i, std::uint32_t j) const {
    if (piece.empty()) return false;
    const std::int32_t a = piece[i], b = piece[j];
    return a >= 0 && b >= 0 && a != b && origin[std::uint32_t(a)] == origin[std::uint32_t(b)];
  }

  // Whether `points` (of xyz) are another object than `solid`'s, as the shape split tells
  // instances apart: most lie outside it by more than its band and some (5%: more than noise)
  // reach farther from its centre or axis than its diameter (a handle or spout stays closer).
  static bool outside(const Solid& solid, const std::vector<Vec3f>& xyz,
                      const std::vector<std::uint32_t>& points) {
    std::size_t in_front = 0, beyond = 0;
    for (std::uint32_t i : points) {
      const float d = solid.in_front(xyz[i]);
      if (d > solid.band) ++in_front;
      if (d > solid.radius) ++beyond;
    }
    return !points.empty() && float(in_front) > solid.share * float(points.size()) &&
           beyond * 20 >= points.size();
  }
};

}  // namespace primlabel::tabletop
