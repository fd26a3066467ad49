#pragma once
// Organised table-top scans for the table-top tests: boxes, upright cans, balls and boxes with
// rounded edges on a table, ray-cast from a Kinect-like camera (shared by the crease-cut,
// shape-split and refinement tests).

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::tabletop::test {

struct Box {
  Vec3f lo, hi;
  std::uint32_t label, rgb;
};

struct Can {  // upright cylinder standing on z = base
  float x, y, radius, base, top;
  std::uint32_t label, rgb;
};

struct Ball {  // resting on the table (z = 0)
  float x, y, radius;
  std::uint32_t label, rgb;
};

// A box [lo, hi] with every edge and corner rounded to `radius` (its faces' flat parts shrink
// by it).
struct RoundedBox {
  Vec3f lo, hi;
  float radius;
  std::uint32_t label, rgb;
};

inline float hit_ball(const Ball& ball, const Vec3f& eye, const Vec3f& ray) {
  const Vec3f o = eye - Vec3f(ball.x, ball.y, ball.radius);
  const float b = o.dot(ray), c = o.squaredNorm() - ball.radius * ball.radius;
  const float disc = b * b - c;
  if (disc < 0) return std::numeric_limits<float>::infinity();
  const float t = -b - std::sqrt(disc);
  return t > 0 ? t : std::numeric_limits<float>::infinity();
}

// Sphere tracing of the rounded box's distance field from where the ray enters its bounds.
inline float hit_rounded_box(const RoundedBox& box, const Vec3f& eye, const Vec3f& ray) {
  const float none = std::numeric_limits<float>::infinity();
  float t0 = 0.0f, t1 = none;
  for (int a = 0; a < 3; ++a) {
    const float ta = (box.lo[a] - eye[a]) / ray[a], tb = (box.hi[a] - eye[a]) / ray[a];
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  if (t0 > t1) return none;
  const Vec3f center = 0.5f * (box.lo + box.hi);
  const Vec3f half = 0.5f * (box.hi - box.lo) - Vec3f::Constant(box.radius);
  float t = t0;
  for (int step = 0; step < 200 && t <= t1 + 1e-4f; ++step) {
    const Vec3f q = ((eye + t * ray) - center).cwiseAbs() - half;
    const float d = q.cwiseMax(0.0f).norm() + std::min(q.maxCoeff(), 0.0f) - box.radius;
    if (d < 1e-5f) return t;
    t += d;
  }
  return none;
}

// Ray parameter of the nearest hit of an upright closed cylinder, or infinity.
inline float hit_can(const Can& can, const Vec3f& eye, const Vec3f& ray) {
  float nearest = std::numeric_limits<float>::infinity();
  const float ox = eye.x() - can.x, oy = eye.y() - can.y;
  const float a = ray.x() * ray.x() + ray.y() * ray.y();
  const float b = 2 * (ox * ray.x() + oy * ray.y());
  const float c = ox * ox + oy * oy - can.radius * can.radius;
  const float disc = b * b - 4 * a * c;
  if (a > 0 && disc >= 0) {
    const float t = (-b - std::sqrt(disc)) / (2 * a);
    const float z = eye.z() + t * ray.z();
    if (t > 0 && z >= can.base && z <= can.top) nearest = t;
  }
  if (ray.z() < 0) {  // the lid
    const float t = (can.top - eye.z()) / ray.z();
    const Vec3f p = eye + t * ray;
    if (std::hypot(p.x() - can.x, p.y() - can.y) <= can.radius) nearest = std::min(nearest, t);
  }
  return nearest;
}

// Boxes, cans, balls and rounded boxes on a 1.2 x 1.3 m table (z = 0), ray-cast into an
// organised 640 x 480 scan (Kinect-like optics) from a camera above and in front, with mOSD
// labels (1 table, 10k+ object k), colours and 0.5 mm noise drawn from `noise_seed`.
inline PointCloud scan(const std::vector<Box>& boxes, const std::vector<Can>& cans = {},
                       unsigned noise_seed = 5, const std::vector<Ball>& balls = {},
                       const std::vector<RoundedBox>& rounded = {}) {
  const int width = 640, height = 480;
  const float focal = 525.0f;
  const Vec3f eye(0.0f, -0.7f, 0.6f), target(0.0f, 0.2f, 0.0f);
  const Vec3f forward = (target - eye).normalized();
  const Vec3f right = forward.cross(Vec3f::UnitZ()).normalized();
  const Vec3f down = forward.cross(right);
  std::mt19937 rng(noise_seed);
  std::normal_distribution<float> noise(0.0f, 0.0005f);
  PointCloud cloud;
  cloud.width = width;
  cloud.height = height;
  cloud.viewpoint.origin = eye;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      const Vec3f ray =
          (forward + (c - width / 2.0f) / focal * right + (r - height / 2.0f) / focal * down)
              .normalized();
      float nearest = std::numeric_limits<float>::infinity();
      std::uint32_t label = 0, rgb = 0;
      if (ray.z() < 0) {
        const float t = -eye.z() / ray.z();
        const Vec3f p = eye + t * ray;
        if (std::abs(p.x()) < 0.6f && p.y() > -0.3f && p.y() < 1.0f) {
          nearest = t;
          label = 1;
          rgb = 0xC8B496;
        }
      }
      for (const Box& box : boxes) {  // slab test
        float t0 = 0.0f, t1 = std::numeric_limits<float>::infinity();
        for (int a = 0; a < 3; ++a) {
          const float ta = (box.lo[a] - eye[a]) / ray[a], tb = (box.hi[a] - eye[a]) / ray[a];
          t0 = std::max(t0, std::min(ta, tb));
          t1 = std::min(t1, std::max(ta, tb));
        }
        if (t0 <= t1 && t0 < nearest) {
          nearest = t0;
          label = box.label;
          rgb = box.rgb;
        }
      }
      const auto take_nearest = [&](const auto& shapes, const auto& hit_shape) {
        for (const auto& shape : shapes) {
          const float t = hit_shape(shape, eye, ray);
          if (t < nearest) {
            nearest = t;
            label = shape.label;
            rgb = shape.rgb;
          }
        }
      };
      take_nearest(cans, hit_can);
      take_nearest(balls, hit_ball);
      take_nearest(rounded, hit_rounded_box);
      const bool hit = std::isfinite(nearest);
      const Vec3f p = hit ? Vec3f(eye + nearest * ray + Vec3f(noise(rng), noise(rng), noise(rng)))
                          : Vec3f(nan, nan, nan);
      cloud.xyz.push_back(p);
      cloud.labels.push_back(hit ? label : 0);
      cloud.rgba.push_back(0xFF000000u | rgb);
    }
  return cloud;
}

}  // namespace primlabel::tabletop::test
