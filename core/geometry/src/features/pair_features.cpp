#include "pair_features_inline.hpp"
#include "primlabel/geometry/features.hpp"

namespace primlabel {

PairFeatures compute_pair_features(const Vec3f& p1, const Vec3f& n1, const Vec3f& p2,
                                   const Vec3f& n2) {
  detail::PairFeatures f;
  const bool ok = detail::pair_features(p1, n1, p2, n2, f);
  return PairFeatures{f.alpha, f.phi, f.theta, f.dist, ok};
}

}  // namespace primlabel
