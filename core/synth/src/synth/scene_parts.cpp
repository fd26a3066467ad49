// The table slab, the random kitchen objects and the standing area the scene kinds share.

#include "scene_parts.hpp"

#include <cmath>

namespace primlabel::synth::detail {
namespace {

constexpr double kTableThickness = 0.04;
constexpr std::uint32_t kTableColor = 0xC8A67A;  // light wood

}  // namespace

Eigen::Isometry3d pose_on_table(double x, double y, double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Vec3d(x, y, 0.0));
  pose.rotate(Eigen::AngleAxisd(yaw, Vec3d::UnitZ()));
  return pose;
}

std::uint32_t pick_color(Rng& rng, std::initializer_list<std::uint32_t> palette) {
  return palette.begin()[rng.below(static_cast<int>(palette.size()))];
}

Candidate random_object(Rng& rng) {
  const double pick = rng.uniform();
  if (pick < 0.30) {
    const Vec3d size(rng.uniform(0.07, 0.22), rng.uniform(0.05, 0.13), rng.uniform(0.05, 0.25));
    return {std::make_shared<BoxShape>(size),
            pick_color(rng, {0xD9482B, 0x2B6CD9, 0xE8C547, 0x6A3D9A, 0xB8865B, 0x2E9E6B})};
  }
  if (pick < 0.50)
    return {std::make_shared<CanShape>(rng.uniform(0.032, 0.055), rng.uniform(0.08, 0.18)),
            pick_color(rng, {0xC0C0C8, 0xC81E1E, 0x1E5AC8, 0xE0A020})};
  if (pick < 0.70) {
    const double radius = rng.uniform(0.035, 0.05);
    const double height = rng.uniform(0.08, 0.12);
    MugShape::Handle handle;
    if (rng.chance(0.8)) {
      handle.major_radius = rng.uniform(0.024, 0.032);
      handle.tube_radius = rng.uniform(0.005, 0.007);
      handle.height = 0.55 * height;
      handle.offset = 0.35 * handle.major_radius;
    }
    return {std::make_shared<MugShape>(radius, height, rng.uniform(0.004, 0.006), 0.008, handle),
            pick_color(rng, {0xF2F2EE, 0x3B5BA5, 0xB22222, 0x2F4F4F, 0xF4A460})};
  }
  if (pick < 0.85) {
    const double radius = rng.uniform(0.06, 0.10);
    return {std::make_shared<BowlShape>(radius, rng.uniform(0.0, 0.25) * radius),
            pick_color(rng, {0xF5F5F0, 0x87CEEB, 0xCD853F, 0x9ACD32})};
  }
  if (pick < 0.925)
    return {std::make_shared<BallShape>(rng.uniform(0.03, 0.06)),
            pick_color(rng, {0xFF8C00, 0x32CD32, 0xDC143C})};
  return {std::make_shared<TorusShape>(rng.uniform(0.04, 0.065), rng.uniform(0.015, 0.025)),
          pick_color(rng, {0xD2691E, 0xFFB6C1, 0x808000})};
}

Scene table_only(Rng& rng, bool random_size) {
  Scene scene;
  scene.table_size = random_size
                         ? Vec3d(rng.uniform(1.2, 1.6), rng.uniform(0.75, 0.9), kTableThickness)
                         : Vec3d(1.4, 0.8, kTableThickness);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Vec3d(0, 0, -kTableThickness));
  // The slab's bottom edges are left out like a standing box's: no sensor above the table sees
  // the underside, so they would only label a scanned face's lower border as edge.
  scene.objects.emplace_back(std::make_shared<BoxShape>(scene.table_size), pose, kTableColor,
                             false);
  return scene;
}

std::optional<Eigen::Isometry3d> StandingArea::place(Rng& rng, double r, double gap) {
  const double x = rng.uniform(-half_x + r, half_x - r);
  const double y = rng.uniform(y_lo + r, y_hi - r);
  const double yaw = rng.uniform(0.0, 2.0 * M_PI);
  if (2 * r > 2 * half_x || 2 * r > y_hi - y_lo) return std::nullopt;
  for (const Footprint& other : placed)
    if (std::hypot(x - other.x, y - other.y) < r + other.r + gap) return std::nullopt;
  placed.push_back({x, y, r});
  return pose_on_table(x, y, yaw);
}

std::optional<Eigen::Isometry3d> StandingArea::place_against(Rng& rng, double r, double gap) {
  const double x = rng.uniform(-half_x + r, half_x - r);
  const double y = rng.uniform(y_lo + r, y_hi - r);
  const double yaw = rng.uniform(0.0, 2.0 * M_PI);
  if (placed.empty() || 2 * r > 2 * half_x || 2 * r > y_hi - y_lo) return std::nullopt;
  const Footprint* nearest = &placed.front();
  for (const Footprint& other : placed)
    if (std::hypot(x - other.x, y - other.y) - other.r <
        std::hypot(x - nearest->x, y - nearest->y) - nearest->r)
      nearest = &other;
  const double away = std::hypot(x - nearest->x, y - nearest->y);
  if (away == 0.0) return std::nullopt;
  const double reach = (r + nearest->r + gap) / away;
  const double nx = nearest->x + reach * (x - nearest->x);
  const double ny = nearest->y + reach * (y - nearest->y);
  if (std::abs(nx) > half_x - r || ny < y_lo + r || ny > y_hi - r) return std::nullopt;
  for (const Footprint& other : placed)
    if (&other != nearest && std::hypot(nx - other.x, ny - other.y) < r + other.r)
      return std::nullopt;
  placed.push_back({nx, ny, r});
  return pose_on_table(nx, ny, yaw);
}

}  // namespace primlabel::synth::detail
