#pragma once
// What every cloud a reader returns must satisfy, whatever the file said: one entry per point in
// every attribute, and a shape that covers the points. A violation traps, so libFuzzer keeps it.

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::fuzz {

inline void check_cloud(const PointCloud& cloud) {
  const std::size_t n = cloud.size();
  auto per_point = [n](std::size_t entries) { return entries == 0 || entries == n; };
  if (!per_point(cloud.normals.size()) || !per_point(cloud.curvature.size()) ||
      !per_point(cloud.labels.size()) || !per_point(cloud.rgba.size()))
    __builtin_trap();
  for (const FloatField& field : cloud.fields)
    if (field.count < 1 || field.values.size() != n * static_cast<std::size_t>(field.count))
      __builtin_trap();
  if (std::size_t{cloud.width} * cloud.height != n) __builtin_trap();
}

}  // namespace primlabel::fuzz
