#pragma once
// Points a refinement step found to be other objects than each other (the shape split's pieces of
// one cluster), so that later steps do not join them again: the occlusion merge links a can to
// the box it stands in front of exactly as it links the two halves of one object.

#include <cstdint>
#include <vector>

namespace primlabel::tabletop {

struct KeptApart {
  std::vector<std::int32_t> piece;    // per input point: its piece, -1 outside cut clusters;
                                      // empty when nothing was cut
  std::vector<std::uint32_t> origin;  // per piece: the cluster it was cut from

  // Whether points i and j lie in different pieces of one cluster.
  bool apart(std::uint32_t i, std::uint32_t j) const {
    if (piece.empty()) return false;
    const std::int32_t a = piece[i], b = piece[j];
    return a >= 0 && b >= 0 && a != b && origin[std::uint32_t(a)] == origin[std::uint32_t(b)];
  }
};

}  // namespace primlabel::tabletop
