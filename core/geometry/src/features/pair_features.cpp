#include "pair_features_inline.hpp"
#include "primlabel/geometry/features.hpp"

namespace primlabel {

bool compute_pair_features(const Vec3f& p1, const Vec3f& n1, const Vec3f& p2, const Vec3f& n2,
                           float& f1, float& f2, float& f3, float& f4) {
  detail::PairFeatures f;
  const bool ok = detail::pair_features(p1, n1, p2, n2, f);
  f1 = f.alpha;
  f2 = f.phi;
  f3 = f.theta;
  f4 = f.dist;
  return ok;
}

}  // namespace primlabel
