// Scene composition: the table slab and randomly chosen, sized and posed kitchen objects on it.

#include "primlabel/synth/scene.hpp"

#include <array>
#include <cmath>
#include <optional>

#include "primlabel/synth/random.hpp"

namespace primlabel::synth {
namespace {

constexpr double kTableThickness = 0.04;
constexpr std::uint32_t kTableColor = 0xC8A67A;  // light wood

Eigen::Isometry3d pose_on_table(double x, double y, double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Vec3d(x, y, 0.0));
  pose.rotate(Eigen::AngleAxisd(yaw, Vec3d::UnitZ()));
  return pose;
}

std::uint32_t pick_color(Rng& rng, std::initializer_list<std::uint32_t> palette) {
  return palette.begin()[rng.below(static_cast<int>(palette.size()))];
}

struct Candidate {
  std::shared_ptr<const Shape> shape;
  std::uint32_t rgb;
};

// Kitchen objects in realistic sizes: boxes (tea, cereal, crackers), cans, mugs and cups,
// bowls, and a few balls and rings.
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

// The front part of a table where objects stand (x in [-half_x, half_x], y in [y_lo, y_hi]) and
// the footprints placed on it so far.
struct StandingArea {
  struct Footprint {
    double x, y, r;
  };
  double half_x, y_lo, y_hi;
  std::vector<Footprint> placed;

  // A random spot and turn for a footprint of radius r, at least `gap` from every placed one; it
  // is then placed. Nothing when the draw lands too close or r does not fit.
  std::optional<Eigen::Isometry3d> place(Rng& rng, double r, double gap) {
    const double x = rng.uniform(-half_x + r, half_x - r);
    const double y = rng.uniform(y_lo + r, y_hi - r);
    const double yaw = rng.uniform(0.0, 2.0 * M_PI);
    if (2 * r > 2 * half_x || 2 * r > y_hi - y_lo) return std::nullopt;
    for (const Footprint& other : placed)
      if (std::hypot(x - other.x, y - other.y) < r + other.r + gap) return std::nullopt;
    placed.push_back({x, y, r});
    return pose_on_table(x, y, yaw);
  }
};

Scene random_table_scene(std::uint64_t seed, const TableSceneOptions& options) {
  Rng rng(mix_seed(seed, 1));
  Scene scene = table_only(rng, true);
  const int wanted =
      options.min_objects + rng.below(std::max(options.max_objects - options.min_objects + 1, 1));
  // Objects stand together on the front part of the table, as in the paper's scenes, where
  // both sensors see them at 0.7-1.2 m.
  const double y_lo = -0.5 * scene.table_size.y() + 0.1;
  StandingArea area{std::min(0.3, 0.5 * scene.table_size.x() - 0.08),
                    y_lo,
                    std::min(y_lo + 0.45, 0.5 * scene.table_size.y() - 0.1),
                    {}};
  for (int attempt = 0; attempt < 1000 && static_cast<int>(area.placed.size()) < wanted;
       ++attempt) {
    Candidate candidate = random_object(rng);
    const double r = candidate.shape->footprint_radius();
    if (const auto pose = area.place(rng, r, options.min_gap))
      scene.objects.emplace_back(std::move(candidate.shape), *pose, candidate.rgb, true);
  }
  return scene;
}

// A crowded table: objects 3-10 mm apart over the front of the table, a third of the picks
// books (flat boxes), and a box on top of about a third of the boxes, as in the cluttered
// scenes of the Object Segmentation Database.
Scene clutter_scene(std::uint64_t seed) {
  Rng rng(mix_seed(seed, 4));
  Scene scene = table_only(rng, true);
  const int wanted = 8 + rng.below(7);
  const double y_lo = -0.5 * scene.table_size.y() + 0.08;
  StandingArea area{std::min(0.35, 0.5 * scene.table_size.x() - 0.08),
                    y_lo,
                    std::min(y_lo + 0.5, 0.5 * scene.table_size.y() - 0.08),
                    {}};
  for (int attempt = 0; attempt < 2000 && static_cast<int>(area.placed.size()) < wanted;
       ++attempt) {
    Candidate candidate =
        rng.chance(0.33)
            ? Candidate{std::make_shared<BoxShape>(Vec3d(rng.uniform(0.14, 0.24),
                                                         rng.uniform(0.10, 0.17),
                                                         rng.uniform(0.015, 0.05))),
                        pick_color(rng, {0x8B0000, 0x1F3A93, 0x2E8B57, 0xF0E68C, 0x4B0082})}
            : random_object(rng);
    const double gap = rng.uniform(0.003, 0.01);
    const auto pose = area.place(rng, candidate.shape->footprint_radius(), gap);
    if (!pose) continue;
    const auto* box = dynamic_cast<const BoxShape*>(candidate.shape.get());
    scene.objects.emplace_back(candidate.shape, *pose, candidate.rgb, true);
    if (box && rng.chance(0.35)) {  // a smaller box on top, turned a little
      const Vec3d below = box->size();
      const Vec3d size(rng.uniform(0.5, 0.9) * below.x(), rng.uniform(0.5, 0.9) * below.y(),
                       rng.uniform(0.03, 0.12));
      Eigen::Isometry3d on_top = *pose;
      on_top.rotate(Eigen::AngleAxisd(rng.uniform(-0.3, 0.3), Vec3d::UnitZ()));
      on_top.pretranslate(Vec3d(0, 0, below.z()));
      scene.objects.emplace_back(std::make_shared<BoxShape>(size), on_top,
                                 pick_color(rng, {0xD9482B, 0x2B6CD9, 0xE8C547, 0x6A3D9A}), true);
    }
  }
  return scene;
}

Scene primitives_scene(std::uint64_t seed) {
  Rng rng(mix_seed(seed, 2));
  Scene scene = table_only(rng, false);
  MugShape::Handle handle{0.028, 0.006, 0.055, 0.01};
  const std::array<Candidate, 6> shapes = {{
      {std::make_shared<BoxShape>(Vec3d(0.14, 0.09, 0.11)), 0xD9482B},
      {std::make_shared<CanShape>(0.037, 0.12), 0xC0C0C8},
      {std::make_shared<MugShape>(0.042, 0.10, 0.005, 0.008, handle), 0xF2F2EE},
      {std::make_shared<BowlShape>(0.08, 0.01), 0x87CEEB},
      {std::make_shared<BallShape>(0.045), 0xFF8C00},
      {std::make_shared<TorusShape>(0.055, 0.022), 0xD2691E},
  }};
  // Two rows of three; the seed only turns them a little.
  const std::array<double, 6> default_yaw = {0.4, 0.0, 0.0, 0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    const double x = -0.3 + 0.3 * static_cast<double>(i % 3);
    const double y = i < 3 ? -0.12 : 0.15;
    const double yaw = default_yaw[i] + rng.uniform(-0.3, 0.3);
    scene.objects.emplace_back(shapes[i].shape, pose_on_table(x, y, yaw), shapes[i].rgb, true);
  }
  return scene;
}

}  // namespace

SceneObject::SceneObject(std::shared_ptr<const Shape> shape_in, const Eigen::Isometry3d& pose,
                         std::uint32_t rgb_in, bool on_support_in)
    : shape(std::move(shape_in)),
      world_from_local(pose),
      local_from_world(pose.inverse()),
      rgb(rgb_in),
      on_support(on_support_in),
      bound_center(pose * shape->bound_center()),
      bound_radius(shape->bound_radius()) {}

std::optional<SceneHit> Scene::cast(const Ray& ray, double t_min, double t_max) const {
  std::optional<SceneHit> best;
  double limit = t_max;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const SceneObject& object = objects[i];
    // Cheap rejection by the bounding sphere.
    const Vec3d oc = ray.origin - object.bound_center;
    const double b = oc.dot(ray.dir);
    const double c = oc.squaredNorm() - object.bound_radius * object.bound_radius;
    const double disc = b * b - c;
    if (disc < 0 || -b + std::sqrt(disc) <= t_min || -b - std::sqrt(disc) >= limit) continue;

    const Ray local{object.local_from_world * ray.origin,
                    object.local_from_world.linear() * ray.dir};
    SurfaceHit hit;
    if (!object.shape->intersect(local, t_min, limit, hit)) continue;
    limit = hit.t;
    best = SceneHit{hit.t, static_cast<int>(i), hit.part,
                    object.world_from_local.linear() * hit.normal};
  }
  return best;
}

bool Scene::occluded(const Vec3d& from, const Vec3d& to) const {
  const Vec3d delta = to - from;
  const double length = delta.norm();
  // Stop short of the target surface itself (0.1 mm) so it does not shadow its own point.
  return cast(Ray{from, delta / length}, 1e-6, length - 1e-4).has_value();
}

Scene make_scene(SceneKind kind, std::uint64_t seed, const TableSceneOptions& options) {
  switch (kind) {
    case SceneKind::kPrimitives:
      return primitives_scene(seed);
    case SceneKind::kEmptyTable: {
      Rng rng(mix_seed(seed, 3));
      return table_only(rng, false);
    }
    case SceneKind::kClutter:
      return clutter_scene(seed);
    case SceneKind::kTable:
      break;
  }
  return random_table_scene(seed, options);
}

std::string describe_objects(const Scene& scene) {
  std::string out;
  for (const SceneObject& object : scene.objects) {
    if (!object.on_support) continue;
    out += out.empty() ? "" : ",";
    out += object.shape->kind();
  }
  return out;
}

}  // namespace primlabel::synth
