// The crowded table's hard cases: groups of objects composed in a frame of their own (a box or
// book leaning on a box, a stack of nearly one footprint, a can beside a box of its height and
// colour, two boxes face to face), placed first, then single objects around them, half of those
// slid against a neighbour.

#include "crowded_scene.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "primlabel/synth/random.hpp"
#include "scene_parts.hpp"

namespace primlabel::synth::detail {
namespace {

constexpr double kContactGap = 0.003;  // "in contact": at most this far apart
constexpr double kDeg = M_PI / 180.0;

struct Member {
  std::shared_ptr<const Shape> shape;
  Eigen::Isometry3d pose;  // in the group's frame, whose plane z = 0 is the table top
  std::uint32_t rgb;
};
using Group = std::vector<Member>;

Eigen::Isometry3d at(double x, double y, double z, double yaw = 0.0) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Vec3d(x, y, z));
  pose.rotate(Eigen::AngleAxisd(yaw, Vec3d::UnitZ()));
  return pose;
}

// Draws in a fixed order: a constructor's or function's arguments are evaluated in none, and the
// scene must be the same whatever the compiler.
Vec3d draw(Rng& rng, const Vec3d& lo, const Vec3d& hi) {
  const double x = rng.uniform(lo.x(), hi.x());
  const double y = rng.uniform(lo.y(), hi.y());
  const double z = rng.uniform(lo.z(), hi.z());
  return Vec3d(x, y, z);
}

std::shared_ptr<const Shape> box(const Vec3d& size) { return std::make_shared<BoxShape>(size); }

std::uint32_t box_color(Rng& rng) {
  return pick_color(rng, {0xD9482B, 0x2B6CD9, 0xE8C547, 0x6A3D9A, 0xB8865B, 0x2E9E6B});
}

std::uint32_t book_color(Rng& rng) {
  return pick_color(rng, {0x8B0000, 0x1F3A93, 0x2E8B57, 0xF0E68C, 0x4B0082});
}

// A book or a cereal box standing on its bottom edge, tilted 12-35 degrees onto a box behind it:
// when it is longer than the box is high it rests on the box's top edge, else its top edge
// rests on the box's face. The leaned-on face is the plane y = 0 of the group.
Group leaning_pair(Rng& rng) {
  const Vec3d support = draw(rng, {0.12, 0.06, 0.10}, {0.22, 0.12, 0.22});
  const bool book = rng.chance(0.6);
  // Width along x, thickness along y, length up (it stands on a long, thin side).
  const Vec3d leaning = book ? draw(rng, {0.13, 0.015, 0.18}, {0.20, 0.035, 0.26})
                             : draw(rng, {0.14, 0.04, 0.20}, {0.22, 0.07, 0.30});
  const double tilt = rng.uniform(12.0, 35.0) * kDeg;
  // How far in front of the face its pivot edge stands for its face to touch the box, plus up to
  // 2 mm so that the two solids never overlap.
  const double reach = std::min(leaning.z() * std::sin(tilt), support.z() * std::tan(tilt)) +
                       rng.uniform(0.0, 0.002);
  // Turned about its bottom edge on the box's side (local y = +thickness/2, z = 0): the rest of
  // its bottom rises off the table, its top moves toward the box.
  Eigen::Isometry3d pose = at(rng.uniform(-0.25, 0.25) * support.x(), -reach, 0.0);
  pose.rotate(Eigen::AngleAxisd(-tilt, Vec3d::UnitX()));
  pose.translate(Vec3d(0.0, -0.5 * leaning.y(), 0.0));
  return {{box(support), at(0.0, 0.5 * support.y(), 0.0), box_color(rng)},
          {box(leaning), pose, book ? book_color(rng) : box_color(rng)}};
}

// A box on a box of nearly its footprint (each side 93-100% of the one below, turned by at most
// 4.6 degrees), or a can on a can of the same radius.
Group similar_stack(Rng& rng) {
  if (rng.chance(0.7)) {
    const Vec3d lower = draw(rng, {0.09, 0.07, 0.04}, {0.20, 0.14, 0.14});
    const Vec3d upper =
        draw(rng, {0.93 * lower.x(), 0.93 * lower.y(), 0.03}, {lower.x(), lower.y(), 0.12});
    const Vec3d shift = draw(rng, {-0.004, -0.004, 0.0}, {0.004, 0.004, 0.0});
    const Eigen::Isometry3d on_top = at(shift.x(), shift.y(), lower.z(), rng.uniform(-0.08, 0.08));
    return {{box(lower), at(0, 0, 0), box_color(rng)}, {box(upper), on_top, box_color(rng)}};
  }
  const double radius = rng.uniform(0.033, 0.045);
  const double lower_height = rng.uniform(0.05, 0.12);
  const double upper_height = rng.uniform(0.05, 0.12);
  const Vec3d shift = draw(rng, {-0.003, -0.003, 0.0}, {0.003, 0.003, 0.0});
  const auto can_color = [&] { return pick_color(rng, {0xC0C0C8, 0xC81E1E, 0x1E5AC8, 0xE0A020}); };
  return {{std::make_shared<CanShape>(radius, lower_height), at(0, 0, 0), can_color()},
          {std::make_shared<CanShape>(radius, upper_height), at(shift.x(), shift.y(), lower_height),
           can_color()}};
}

// A can 0-3 mm beside a box of its height and colour: side by side they link across no table.
Group can_beside_box(Rng& rng) {
  const double height = rng.uniform(0.08, 0.18);
  const Vec3d footprint = draw(rng, {0.08, 0.06, 0.0}, {0.20, 0.12, 0.0});
  const Vec3d size(footprint.x(), footprint.y(), height);
  const double radius = rng.uniform(0.032, 0.05);
  const std::uint32_t rgb = pick_color(rng, {0xC81E1E, 0x1E5AC8, 0xE0A020, 0xC0C0C8, 0x2E9E6B});
  const double gap = rng.uniform(0.0, kContactGap);
  return {{box(size), at(0, 0, 0), rgb},
          {std::make_shared<CanShape>(radius, height),
           at(rng.uniform(-0.3, 0.3) * size.x(), 0.5 * size.y() + radius + gap, 0.0), rgb}};
}

// Two boxes face to face, 0-3 mm apart.
Group boxes_face_to_face(Rng& rng) {
  const Vec3d a = draw(rng, {0.05, 0.08, 0.06}, {0.12, 0.16, 0.22});
  const Vec3d b = draw(rng, {0.05, 0.08, 0.06}, {0.12, 0.16, 0.22});
  const double gap = rng.uniform(0.0, kContactGap);
  return {{box(a), at(-0.5 * (a.x() + gap), 0, 0), box_color(rng)},
          {box(b), at(0.5 * (b.x() + gap), rng.uniform(-0.02, 0.02), 0), box_color(rng)}};
}

// A circle on the table around which the group lies: every shape lies in the vertical cylinder
// of its footprint radius (shape frame), and that cylinder, tilted or not, projects into the hull
// of its two end discs.
struct Circle {
  Eigen::Vector2d center;
  double radius;
};

Circle enclosing_circle(const Group& group) {
  struct Disc {
    Eigen::Vector2d center;
    double radius;
  };
  std::vector<Disc> discs;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const Member& member : group) {
    const double r = member.shape->footprint_radius();
    // Every shape's bounding sphere is centred at half its height.
    const double height = 2.0 * member.shape->bound_center().z();
    for (const double z : {0.0, height}) {
      const Eigen::Vector2d end = (member.pose * Vec3d(0, 0, z)).head<2>();
      discs.push_back({end, r});
      lo = lo.cwiseMin(end - Eigen::Vector2d::Constant(r));
      hi = hi.cwiseMax(end + Eigen::Vector2d::Constant(r));
    }
  }
  Circle circle{0.5 * (lo + hi), 0.0};
  for (const Disc& disc : discs)
    circle.radius = std::max(circle.radius, (disc.center - circle.center).norm() + disc.radius);
  return circle;
}

// The share of an object a viewpoint sees past the others: of rays from `eye` through a grid
// over the object's bounding sphere that would hit it alone, those whose first hit it is.
double visible_share(const Scene& scene, int index, const Vec3d& eye) {
  constexpr int kGrid = 16;
  const SceneObject& object = scene.objects[index];
  const Vec3d forward = (object.bound_center - eye).normalized();
  const Vec3d right = forward.cross(Vec3d::UnitZ()).normalized();
  const Vec3d up = right.cross(forward);
  int alone = 0, seen = 0;
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j) {
      const double u = (2.0 * (i + 0.5) / kGrid - 1.0) * object.bound_radius;
      const double v = (2.0 * (j + 0.5) / kGrid - 1.0) * object.bound_radius;
      const Ray ray{eye, (object.bound_center + u * right + v * up - eye).normalized()};
      SurfaceHit hit;
      const Ray local{object.local_from_world * ray.origin,
                      object.local_from_world.linear() * ray.dir};
      if (!object.shape->intersect(local, 1e-6, 10.0, hit)) continue;
      ++alone;
      const auto first = scene.cast(ray, 1e-6, 10.0);
      seen += first && first->object == index;
    }
  return alone > 0 ? double(seen) / alone : 0.0;
}

// Every object seen in good part (kMinVisibleShare) from both ends of where kinect_for_scene
// puts the sensor at its lowest and farthest: a crowded table hides objects behind others, and
// one the scan cannot see would only count against the table-top stage.
constexpr double kMinVisibleShare = 0.3;

bool everything_in_view(const Scene& scene) {
  const double front = -0.5 * scene.table_size.y();
  for (const Vec3d& eye : {Vec3d(-0.08, front - 0.5, 0.65), Vec3d(0.08, front - 0.5, 0.65)})
    for (int i = 1; i < static_cast<int>(scene.objects.size()); ++i)
      if (visible_share(scene, i, eye) < kMinVisibleShare) return false;
  return true;
}

// Places the group at the first free spot of `attempts` draws of `spot` (a footprint radius to
// a pose on the table) where it leaves everything in view; false when there was none.
template <typename Spot>
bool place_group(const Group& group, Spot&& spot, int attempts, StandingArea& area, Scene& scene) {
  const Circle circle = enclosing_circle(group);
  for (int attempt = 0; attempt < attempts; ++attempt) {
    const std::optional<Eigen::Isometry3d> pose = spot(circle.radius);
    if (!pose) continue;
    const Eigen::Isometry3d world_from_group =
        *pose * Eigen::Translation3d(-circle.center.x(), -circle.center.y(), 0.0);
    for (const Member& member : group)
      scene.objects.emplace_back(member.shape, world_from_group * member.pose, member.rgb, true);
    if (everything_in_view(scene)) return true;
    scene.objects.erase(scene.objects.end() - static_cast<std::ptrdiff_t>(group.size()),
                        scene.objects.end());
    area.placed.pop_back();
  }
  return false;
}

}  // namespace

Scene crowded_scene(std::uint64_t seed) {
  Rng rng(mix_seed(seed, 5));
  Scene scene = table_only(rng, true);
  const int wanted = 8 + rng.below(7);  // objects in all, stacked and leaning ones included
  const double y_lo = -0.5 * scene.table_size.y() + 0.08;
  StandingArea area{std::min(0.35, 0.5 * scene.table_size.x() - 0.08),
                    y_lo,
                    std::min(y_lo + 0.5, 0.5 * scene.table_size.y() - 0.08),
                    {}};
  const auto objects = [&] { return static_cast<int>(scene.objects.size()) - 1; };
  // The groups first: they need the most room.
  for (const auto make : {leaning_pair, can_beside_box, similar_stack, boxes_face_to_face}) {
    if (!rng.chance(0.85)) continue;
    const Group group = make(rng);
    if (objects() + static_cast<int>(group.size()) > wanted) continue;
    const double gap = rng.uniform(kContactGap, 0.01);
    place_group(
        group, [&](double r) { return area.place(rng, r, gap); }, 300, area, scene);
  }
  for (int attempt = 0; attempt < 2000 && objects() < wanted; ++attempt) {
    Candidate candidate =
        rng.chance(0.33)  // a book lying flat, as on clutter's tables
            ? Candidate{box(draw(rng, {0.14, 0.10, 0.015}, {0.24, 0.17, 0.05})), book_color(rng)}
            : random_object(rng);
    // Half of them against a neighbour: drawn spots alone seldom land within contact distance.
    const bool touching = rng.chance(0.5);
    const double gap = touching ? rng.uniform(0.0, kContactGap) : rng.uniform(kContactGap, 0.01);
    const auto spot = [&](double r) {
      return touching ? area.place_against(rng, r, gap) : area.place(rng, r, gap);
    };
    place_group({{candidate.shape, Eigen::Isometry3d::Identity(), candidate.rgb}}, spot, 1, area,
                scene);
  }
  return scene;
}

}  // namespace primlabel::synth::detail
