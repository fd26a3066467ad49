// The scene kinds (table, primitives, empty, clutter) and ray casting into a scene; the crowded
// kind's hard cases are composed in crowded_scene.cpp.

#include "primlabel/synth/scene.hpp"

#include <array>
#include <cmath>

#include "crowded_scene.hpp"
#include "primlabel/synth/random.hpp"
#include "scene_parts.hpp"

namespace primlabel::synth {
namespace {

using detail::Candidate;
using detail::pick_color;
using detail::pose_on_table;
using detail::random_object;
using detail::StandingArea;
using detail::table_only;

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
    case SceneKind::kCrowded:
      return detail::crowded_scene(seed);
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
