#pragma once
// The node feature x_i = [phi(s * descriptor_i), 1] of crf/model.hpp, written into a caller's row:
// the one definition that inference and every training objective share.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>

#include "primlabel/crf/model.hpp"

namespace primlabel::crf::detail {

// The two non-zero tent values of one bin: at `column` (the lower knot's) and column + 1.
struct TentPair {
  std::uint32_t column;
  float lower, upper;
};

// Bin `bin` with scaled value u; a NaN value (never the case for an active point) gives zeros.
inline TentPair tent_pair(float u, int bin, std::span<const float> knots) {
  const int count = static_cast<int>(knots.size());
  if (std::isnan(u)) return {std::uint32_t(bin) * count, 0.0f, 0.0f};
  const float clamped = std::clamp(u, knots.front(), knots.back());
  // The segment [t_a, t_a+1] holding the value (knots are few: a linear scan is fastest).
  int a = 0;
  while (a + 2 < count && clamped > knots[a + 1]) ++a;
  const float t = (clamped - knots[a]) / (knots[a + 1] - knots[a]);
  return {std::uint32_t(bin * count + a), 1.0f - t, t};
}

// The tent features compactly: d pairs, the bias column implied. Knots must not be empty.
inline void tent_pairs(const float* descriptor, int d, float scale, std::span<const float> knots,
                       TentPair* out) {
  for (int b = 0; b < d; ++b) out[b] = tent_pair(scale * descriptor[b], b, knots);
}

// Writes the node_feature_dim() values of x_i to `out` (NaN descriptor values propagate in the
// identity basis, and give zeros in the tent basis).
template <typename T>
void node_features(const float* descriptor, int d, float scale, std::span<const float> knots,
                   T* out) {
  if (knots.empty()) {
    for (int b = 0; b < d; ++b) out[b] = T(scale * descriptor[b]);
    out[d] = T(1);
    return;
  }
  const std::size_t dim = std::size_t(d) * knots.size();
  std::fill_n(out, dim, T(0));
  for (int b = 0; b < d; ++b) {
    const TentPair p = tent_pair(scale * descriptor[b], b, knots);
    out[p.column] = T(p.lower);
    out[p.column + 1] = T(p.upper);
  }
  out[dim] = T(1);
}

template <typename T>
void node_features(const CrfModel& model, const float* descriptor, T* out) {
  node_features(descriptor, model.descriptor_dim, model.feature_scale, model.node_knots, out);
}

}  // namespace primlabel::crf::detail
