#pragma once
// Synthetic surface samples with known parameters for the primitive tests: noisy points, their
// normals (tilted by a few degrees) and uniform outliers.

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::primitives::test {

struct Samples {
  std::vector<Vec3f> xyz, normals;
  std::vector<std::uint32_t> indices() const {
    std::vector<std::uint32_t> out(xyz.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = std::uint32_t(i);
    return out;
  }
};

class SampleMaker {
 public:
  explicit SampleMaker(unsigned seed, double noise = 0.0005, double normal_tilt_deg = 3)
      : rng_(seed), noise_(noise), tilt_(normal_tilt_deg * M_PI / 180) {}

  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng_);
  }
  double gauss(double sigma) { return std::normal_distribution<double>(0, sigma)(rng_); }

  // A surface point with its unit normal, jittered along the normal and tilted.
  void add(Samples& s, const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    const Eigen::Vector3d q = p + gauss(noise_) * n;
    const Eigen::Vector3d jitter(gauss(tilt_), gauss(tilt_), gauss(tilt_));
    s.xyz.push_back(q.cast<float>());
    s.normals.push_back((n + jitter - jitter.dot(n) * n).normalized().cast<float>());
  }
  // Uniform points in the box [lo, hi] with random normals.
  void add_outliers(Samples& s, int count, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    for (int i = 0; i < count; ++i) {
      const Eigen::Vector3d p(uniform(lo.x(), hi.x()), uniform(lo.y(), hi.y()),
                              uniform(lo.z(), hi.z()));
      const Eigen::Vector3d n(gauss(1), gauss(1), gauss(1));
      s.xyz.push_back(p.cast<float>());
      s.normals.push_back(n.normalized().cast<float>());
    }
  }

 private:
  std::mt19937 rng_;
  double noise_, tilt_;
};

inline std::pair<Eigen::Vector3d, Eigen::Vector3d> basis(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d u = axis.unitOrthogonal();
  return {u, axis.cross(u)};
}

// Side of a cylinder seen over `arc` radians; normals out of the axis, or into it (`concave`).
inline void add_cylinder(Samples& s, SampleMaker& m, const Eigen::Vector3d& base,
                         const Eigen::Vector3d& axis, double radius, double height, double arc,
                         int count, bool concave = false) {
  const auto [u, v] = basis(axis);
  for (int i = 0; i < count; ++i) {
    const double a = m.uniform(-arc / 2, arc / 2), h = m.uniform(0, height);
    const Eigen::Vector3d radial = std::cos(a) * u + std::sin(a) * v;
    m.add(s, base + h * axis + radius * radial, concave ? Eigen::Vector3d(-radial) : radial);
  }
}

// Cap of a sphere around `pole` (unit) with half-angle `half_angle`.
inline void add_sphere(Samples& s, SampleMaker& m, const Eigen::Vector3d& center, double radius,
                       const Eigen::Vector3d& pole, double half_angle, int count) {
  const auto [u, v] = basis(pole);
  for (int i = 0; i < count; ++i) {
    const double cos_t = m.uniform(std::cos(half_angle), 1.0), phi = m.uniform(0, 2 * M_PI);
    const double sin_t = std::sqrt(1 - cos_t * cos_t);
    const Eigen::Vector3d d = cos_t * pole + sin_t * (std::cos(phi) * u + std::sin(phi) * v);
    m.add(s, center + radius * d, d);
  }
}

// Torus points with tube angle in [tube_lo, tube_hi] (0 = outermost) all round the axis.
inline void add_torus(Samples& s, SampleMaker& m, const Eigen::Vector3d& center,
                      const Eigen::Vector3d& axis, double major, double minor, double tube_lo,
                      double tube_hi, int count) {
  const auto [u, v] = basis(axis);
  for (int i = 0; i < count; ++i) {
    const double phi = m.uniform(0, 2 * M_PI), theta = m.uniform(tube_lo, tube_hi);
    const Eigen::Vector3d radial = std::cos(phi) * u + std::sin(phi) * v;
    const Eigen::Vector3d n = std::cos(theta) * radial + std::sin(theta) * axis;
    m.add(s, center + major * radial + minor * n, n);
  }
}

// A band `width` wide on both faces of the crease along `direction` through `point`, the faces
// going off along `face_a` and `face_b` (unit, perpendicular to direction).
inline void add_edge_band(Samples& s, SampleMaker& m, const Eigen::Vector3d& point,
                          const Eigen::Vector3d& direction, const Eigen::Vector3d& face_a,
                          const Eigen::Vector3d& face_b, double length, double width, int count) {
  for (int i = 0; i < count; ++i) {
    const bool on_a = i % 2 == 0;
    const Eigen::Vector3d& face = on_a ? face_a : face_b;
    const Eigen::Vector3d& other = on_a ? face_b : face_a;
    Eigen::Vector3d n = direction.cross(face).normalized();
    if (n.dot(other) > 0) n = -n;  // convex: out of the material
    m.add(s, point + m.uniform(-length / 2, length / 2) * direction + m.uniform(0, width) * face,
          n);
  }
}

inline double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180 / M_PI;
}

// Distance from p to the line through q along unit d.
inline double line_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                            const Eigen::Vector3d& d) {
  const Eigen::Vector3d r = p - q;
  return (r - r.dot(d) * d).norm();
}

}  // namespace primlabel::primitives::test
