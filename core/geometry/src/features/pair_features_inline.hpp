#pragma once
// The point-pair features of PCL's pcl::computePairFeatures, written so that every float operation
// happens in the same order as PCL's Eigen::Vector4f code does with SSE (a 4-lane dot product is
// reduced as (x + z) + (y + w), with w = 0). Same inputs therefore give bit-identical angles, and
// histogram bins never disagree with PCL's at bin boundaries.

#include <cmath>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::detail {

inline float dot4(const Vec3f& a, const Vec3f& b) {
  return (a.x() * b.x() + a.z() * b.z()) + (a.y() * b.y() + 0.0f);
}

inline Vec3f cross3(const Vec3f& a, const Vec3f& b) {
  return Vec3f(a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(),
               a.x() * b.y() - a.y() * b.x());
}

struct PairFeatures {
  float alpha;  // f1: angle of n2 in the Darboux frame, [-pi, pi]
  float phi;    // f2: cosine, v . n2
  float theta;  // f3: cosine, u . (p2 - p1) / |p2 - p1|
  float dist;   // f4
};

// Returns false for coincident points or a degenerate frame; the features are then all zero,
// which is what PCL bins for such pairs.
inline bool pair_features(const Vec3f& p1, const Vec3f& n1, const Vec3f& p2, const Vec3f& n2,
                          PairFeatures& f) {
  Vec3f delta = p2 - p1;
  f.dist = std::sqrt(dot4(delta, delta));
  if (f.dist == 0.0f) {
    f = PairFeatures{0.0f, 0.0f, 0.0f, 0.0f};
    return false;
  }
  const float angle1 = dot4(n1, delta) / f.dist;
  const float angle2 = dot4(n2, delta) / f.dist;
  // The source of the pair is the point whose normal makes the smaller angle with the line.
  const Vec3f* u = &n1;
  const Vec3f* target_normal = &n2;
  if (std::acos(std::fabs(angle1)) > std::acos(std::fabs(angle2))) {
    u = &n2;
    target_normal = &n1;
    delta = -delta;
    f.theta = -angle2;
  } else {
    f.theta = angle1;
  }
  Vec3f v = cross3(delta, *u);
  const float v_norm = std::sqrt(dot4(v, v));
  if (v_norm == 0.0f) {
    f = PairFeatures{0.0f, 0.0f, 0.0f, 0.0f};
    return false;
  }
  v = Vec3f(v.x() / v_norm, v.y() / v_norm, v.z() / v_norm);
  const Vec3f w = cross3(*u, v);
  f.phi = dot4(v, *target_normal);
  f.alpha = std::atan2(dot4(w, *target_normal), dot4(*u, *target_normal));
  return true;
}

// Histogram bins exactly as PCL computes them (double arithmetic on the float features).
inline constexpr float kInvTwoPi = 1.0f / (2.0f * static_cast<float>(M_PI));

inline int clamp_bin(double scaled, int bins) {
  int b = static_cast<int>(std::floor(scaled));
  if (b < 0) b = 0;
  if (b >= bins) b = bins - 1;
  return b;
}
inline int angle_bin(float alpha, int bins) {
  return clamp_bin(bins * ((alpha + M_PI) * kInvTwoPi), bins);
}
inline int cosine_bin(float cosine, int bins) {
  return clamp_bin(bins * ((cosine + 1.0) * 0.5), bins);
}

}  // namespace primlabel::detail
