#pragma once
// Histogram bins of many point pairs sharing their first point, four at a time. Used by FPFH and
// PFH; gives exactly the bins of pair_features + angle_bin/cosine_bin (pair_features_inline.hpp).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::detail {

// Structure-of-arrays copy of the second points of a batch of pairs.
struct PairTargets {
  std::vector<float> x, y, z, nx, ny, nz;
  void clear() { x.clear(), y.clear(), z.clear(), nx.clear(), ny.clear(), nz.clear(); }
  void resize(std::size_t n) {
    x.resize(n), y.resize(n), z.resize(n), nx.resize(n), ny.resize(n), nz.resize(n);
  }
  void set(std::size_t j, const Vec3f& p, const Vec3f& n) {
    x[j] = p.x(), y[j] = p.y(), z[j] = p.z(), nx[j] = n.x(), ny[j] = n.y(), nz[j] = n.z();
  }
  void push(const Vec3f& p, const Vec3f& n) {
    x.push_back(p.x()), y.push_back(p.y()), z.push_back(p.z());
    nx.push_back(n.x()), ny.push_back(n.y()), nz.push_back(n.z());
  }
  std::size_t size() const { return x.size(); }
};

// For each of the first `count` targets j, the bins of the pair (p1, n1) -> (target j) with
// `bins` bins per feature: alpha[j], phi[j], theta[j] in [0, bins).
//
// The pair features are symmetric: (target j) -> (p1, n1) gives the same bits, because both
// directions pick the same source point and frame, except when the two angles to the line tie
// (then each direction keeps its own first point) or when a zero's sign can pick the bin. With
// `one_sided`, one_sided[j] is 0 only for pairs where the reversed pair is sure to fall in the
// same bins; 1 where it has to be computed itself (ties within 2e-6, coincident points,
// degenerate frames, bins decided near a boundary, and the scalar tail: a cheap superset).
void pair_bins_batch(const Vec3f& p1, const Vec3f& n1, const PairTargets& targets,
                     std::size_t count, int bins, std::uint8_t* alpha, std::uint8_t* phi,
                     std::uint8_t* theta, std::uint8_t* one_sided = nullptr);

// The bins of one pair by the exact (scalar) path: {alpha, phi, theta}.
void pair_bins_exact(const Vec3f& p1, const Vec3f& n1, const Vec3f& p2, const Vec3f& n2, int bins,
                     std::uint8_t bins_out[3]);

}  // namespace primlabel::detail
