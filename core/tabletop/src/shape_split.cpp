#include "primlabel/tabletop/shape_split.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "disjoint_sets.hpp"
#include "primlabel/geometry/parallel.hpp"
#include "primlabel/primitives/fitters.hpp"
#include "surface_colour.hpp"

namespace primlabel::tabletop {

void ShapeSplitOptions::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  const auto positive = [&](float v, const char* name) {
    if (!(v > 0.0f) || !std::isfinite(v))
      fail(std::string("shape split ") + name + " must be positive, got " + std::to_string(v));
  };
  if (normal_step < 1) fail("shape split normal step must be at least 1 pixel");
  positive(depth_noise_per_m2, "depth noise");
  positive(noise_sigmas, "noise sigmas");
  positive(min_band, "minimum band");
  positive(max_neighbour_gap, "neighbour gap");
  positive(min_radius, "minimum radius");
  if (!(max_radius > min_radius)) fail("shape split radius range is empty");
  if (!(normal_angle_deg > 0.0f && normal_angle_deg < 90.0f))
    fail("shape split normal angle must be in (0, 90) degrees");
  if (!(outside_share > 0.0f && outside_share < 1.0f))
    fail("shape split outside share must be in (0, 1)");
  if (min_instance_points < 3) fail("shape split instances need at least 3 points");
  if (max_instances < 1) fail("shape split needs at least one instance per cluster");
  if (!(seam_explained > 0.0f && seam_explained < 1.0f))
    fail("shape split seam share must be in (0, 1)");
  positive(seam_chromaticity_step, "seam chromaticity step");
  positive(seam_min_rise, "seam rise");
  positive(material_separation, "material separation");
  if (!(upright_deg > 0.0f && upright_deg < 90.0f))
    fail("shape split upright angle must be in (0, 90) degrees");
}

namespace {

using Vec3d = Eigen::Vector3d;
constexpr double kDegree = M_PI / 180.0;
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

// A fitted instance: its surface, and which side of it is outside the object.
struct Instance {
  enum class Kind { kPlane, kConvexCylinder, kConvexSphere, kNoSolid } kind = Kind::kNoSolid;
  Vec3d normal = Vec3d::Zero();  // plane: facing the sensor
  double offset = 0;
  Vec3d axis_point = Vec3d::Zero(), axis = Vec3d::UnitZ();  // cylinder; a sphere's centre
  double radius = 0;
  bool sphere = false;  // a sphere's surface (also when, seen from inside, it bounds no solid)
  std::vector<std::uint32_t> inliers;  // cluster-local ids

  // A curved surface's outward direction at p: away from its axis, or from its centre.
  Vec3d radial(const Vec3d& p) const {
    const Vec3d q = p - axis_point;
    return sphere ? q : Vec3d(q - q.dot(axis) * axis);
  }
  // Signed distance outside the object's solid behind this surface (> 0: in front of it).
  double in_front(const Vec3d& p) const {
    if (kind == Kind::kPlane) return normal.dot(p) + offset;
    return radial(p).norm() - radius;
  }
  // Whether the solid behind this surface is a can's or a ball's: it bounds it all round.
  bool convex_solid() const { return kind == Kind::kConvexCylinder || kind == Kind::kConvexSphere; }
};

class ShapeSplitter {
 public:
  ShapeSplitter(const PointCloud& cloud, const std::vector<float>& height, const Vec3f& up,
                const ShapeSplitOptions& options)
      : xyz_(cloud.xyz),
        rgba_(cloud.rgba),
        height_of_(height),
        up_(up.cast<double>().normalized()),
        width_(int(cloud.width)),
        height_(int(cloud.height)),
        viewpoint_(cloud.viewpoint.origin),
        options_(options),
        local_(cloud.xyz.size(), kNone),
        normals_(cloud.xyz.size(), Vec3f::Constant(std::numeric_limits<float>::quiet_NaN())) {}

  std::vector<std::vector<std::uint32_t>> split(const std::vector<std::uint32_t>& cluster) {
    solids_.clear();
    if (cluster.size() < options_.min_object_points) return {cluster};
    cluster_ = &cluster;
    for (std::uint32_t k = 0; k < cluster.size(); ++k) local_[cluster[k]] = k;
    set_band();
    colour_apart_.clear();
    grid_normals();
    fit_instances();
    std::vector<std::vector<std::uint32_t>> pieces;
    if (cluster.size() < 2 * options_.min_object_points) {
      // Too small to hold two objects, but it may be a ball that another cluster lies outside.
      pieces = {cluster};
    } else {
      cut_planes_by_cans();
      if (colour_known()) {
        cut_at_colour_seams();
        cut_mixed_materials();
      }
      assign_the_rest();
      pieces = join_instances();
    }
    record_solids();
    for (std::uint32_t i : cluster) {
      local_[i] = kNone;
      normals_[i] = Vec3f::Constant(std::numeric_limits<float>::quiet_NaN());
    }
    return pieces;
  }

  // The balls and cans fitted in the last cluster, for later steps (KeptApart::solids).
  const std::vector<KeptApart::Solid>& solids() const { return solids_; }

 private:
  // The cluster-local id of the pixel (row, col), kNone when outside the cluster.
  std::uint32_t at(int row, int col) const {
    if (row < 0 || col < 0 || row >= height_ || col >= width_) return kNone;
    return local_[std::size_t(row) * std::size_t(width_) + std::size_t(col)];
  }
  std::uint32_t global(std::uint32_t local) const { return (*cluster_)[local]; }
  Vec3d point(std::uint32_t local) const { return xyz_[global(local)].cast<double>(); }
  bool touching(std::uint32_t a, std::uint32_t b, int pixels) const {
    return (xyz_[global(a)] - xyz_[global(b)]).norm() <= options_.max_neighbour_gap * float(pixels);
  }
  // Calls f(neighbour) for the 8 pixel neighbours of `local` in the cluster that touch it in 3D.
  template <typename F>
  void for_each_touching(std::uint32_t local, F&& f) const {
    const std::uint32_t i = global(local);
    const int row = int(i / std::uint32_t(width_)), col = int(i % std::uint32_t(width_));
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) {
        if (dr == 0 && dc == 0) continue;
        const std::uint32_t j = at(row + dr, col + dc);
        if (j != kNone && touching(local, j, 1)) f(j);
      }
  }

  void set_band() {
    double range = 0;
    for (std::uint32_t i : *cluster_) range += (xyz_[i] - viewpoint_).norm();
    range /= double(cluster_->size());
    band_ = std::max(double(options_.min_band),
                     options_.noise_sigmas * options_.depth_noise_per_m2 * range * range);
  }

  // Central differences on the pixel grid, normal_step pixels either side (1 where the farther
  // pixel is not this surface's), facing the sensor.
  void grid_normals() {
    for (std::uint32_t k = 0; k < cluster_->size(); ++k) {
      const std::uint32_t i = global(k);
      const int row = int(i / std::uint32_t(width_)), col = int(i % std::uint32_t(width_));
      const auto difference = [&](int dr, int dc) -> std::optional<Vec3f> {
        for (int step = options_.normal_step; step >= 1; --step) {
          const std::uint32_t a = at(row - dr * step, col - dc * step);
          const std::uint32_t b = at(row + dr * step, col + dc * step);
          if (a != kNone && b != kNone && touching(a, k, step) && touching(b, k, step))
            return xyz_[global(b)] - xyz_[global(a)];
        }
        return std::nullopt;
      };
      const auto across = difference(0, 1), down = difference(1, 0);
      if (!across || !down) continue;
      Vec3f n = across->cross(*down);
      const float length = n.norm();
      if (!(length > 0.0f)) continue;
      n /= length;
      if (n.dot(viewpoint_ - xyz_[i]) < 0.0f) n = -n;
      normals_[i] = n;
    }
  }

  // Fewer cylinder hypotheses, each scored on fewer points: a cylinder hypothesis costs several
  // times a plane's, and a can missed in one round is drawn again in the next, from fewer points.
  // Least squares on a strided subset of the inliers: it was most of the cost.
  primitives::FitSettings fit_settings(primitives::PrimitiveKind kind) const {
    const bool plane = kind == primitives::PrimitiveKind::kPlane;
    primitives::FitSettings settings;
    settings.distance_threshold = band_;
    settings.normal_angle_deg = options_.normal_angle_deg;
    settings.hypotheses = plane ? 60 : 40;
    settings.max_scoring_points = plane ? 600 : 300;
    settings.max_refine_points = 800;  // plenty for 5 parameters; least squares dominated
    settings.refine_iterations = 10;
    // The round's own plane competes with each cylinder (the larger connected piece wins), so
    // the fitter's refit of a plane to judge a cylinder is not needed: same objects, -4% a frame.
    settings.prefer_simpler = false;
    settings.min_radius = options_.min_radius;
    settings.max_radius = options_.max_radius;
    return settings;
  }

  // The instance a fit describes, with no inliers yet; nothing for models other than planes,
  // cylinders and spheres.
  static std::optional<Instance> instance_of(const primitives::Model& model) {
    Instance instance;
    if (const auto* plane = std::get_if<primitives::PlaneModel>(&model)) {
      instance.kind = Instance::Kind::kPlane;
      instance.normal = plane->normal;
      instance.offset = plane->offset;
      return instance;
    }
    if (const auto* cylinder = std::get_if<primitives::CylinderModel>(&model)) {
      instance.kind = Instance::Kind::kConvexCylinder;
      instance.axis_point = cylinder->center;
      instance.axis = cylinder->axis.normalized();
      instance.radius = cylinder->radius;
      return instance;
    }
    if (const auto* sphere = std::get_if<primitives::SphereModel>(&model)) {
      instance.kind = Instance::Kind::kConvexSphere;
      instance.sphere = true;
      instance.axis_point = sphere->center;
      instance.radius = sphere->radius;
      return instance;
    }
    return std::nullopt;
  }

  bool explains(const Instance& instance, std::uint32_t local) const {
    const Vec3f& nf = normals_[global(local)];
    if (!nf.allFinite()) return false;
    const Vec3d p = point(local), n = nf.cast<double>();
    Vec3d surface_normal;
    if (instance.kind == Instance::Kind::kPlane) {
      surface_normal = instance.normal;
    } else {
      surface_normal = instance.radial(p).normalized();
    }
    return std::abs(instance.in_front(p)) <= band_ &&
           std::abs(surface_normal.dot(n)) >= std::cos(options_.normal_angle_deg * kDegree);
  }

  // The largest image-connected piece of the free points `instance` explains (ties: the piece
  // with the lowest id).
  std::vector<std::uint32_t> largest_piece(const Instance& instance,
                                           const std::vector<std::uint32_t>& free) {
    std::fill(mark_.begin(), mark_.end(), 0);
    for (std::uint32_t k : free)
      if (explains(instance, k)) mark_[k] = 1;
    std::vector<std::uint32_t> best, piece;
    for (std::uint32_t k : free) {
      if (mark_[k] != 1) continue;
      piece.clear();
      mark_[k] = 2;
      piece.push_back(k);
      for (std::size_t q = 0; q < piece.size(); ++q)
        for_each_touching(piece[q], [&](std::uint32_t j) {
          if (mark_[j] == 1) {
            mark_[j] = 2;
            piece.push_back(j);
          }
        });
      if (piece.size() > best.size()) best = piece;
    }
    std::sort(best.begin(), best.end());
    return best;
  }

  void record_solids() {
    for (const Instance& instance : instances_) {
      const bool can = instance.kind == Instance::Kind::kConvexCylinder;
      if ((instance.kind != Instance::Kind::kConvexSphere && !can) ||
          instance.inliers.size() < options_.min_object_points)
        continue;
      if (can && rounded_box_edge(instance)) continue;
      KeptApart::Solid solid;
      solid.centre = instance.axis_point.cast<float>();
      solid.axis = instance.axis.cast<float>();
      solid.radius = float(instance.radius);
      solid.ball = instance.sphere;
      solid.band = float(band_);
      solid.share = options_.outside_share;
      solid.anchor = global(instance.inliers.front());
      solids_.push_back(solid);
    }
  }

  // Planes, cylinders and balls, one after the other, each the largest connected piece of its
  // inliers among the points no earlier instance took.
  void fit_instances() {
    instances_.clear();
    owner_.assign(cluster_->size(), kNone);
    mark_.assign(cluster_->size(), 0);
    std::vector<std::uint32_t> free;
    for (std::uint32_t k = 0; k < cluster_->size(); ++k)
      if (normals_[global(k)].allFinite()) free.push_back(k);
    for (int round = 0; round < options_.max_instances; ++round) {
      if (free.size() < options_.min_instance_points) break;
      std::vector<std::uint32_t> indices(free.size());
      for (std::size_t k = 0; k < free.size(); ++k) indices[k] = global(free[k]);
      const primitives::SegmentPoints points{xyz_, normals_, indices};
      const std::uint64_t seed = options_.seed + 2 * std::uint64_t(round);
      std::optional<Instance> best;
      std::vector<std::uint32_t> best_inliers;
      const auto offer = [&](Instance instance, std::vector<std::uint32_t> inliers) {
        if (inliers.size() > best_inliers.size()) {
          best = std::move(instance);
          best_inliers = std::move(inliers);
        }
      };
      for (const auto kind :
           {primitives::PrimitiveKind::kPlane, primitives::PrimitiveKind::kCylinder}) {
        const auto fit =
            primitives::fit_model(kind, points, fit_settings(kind),
                                  seed + (kind == primitives::PrimitiveKind::kPlane ? 0 : 1));
        if (!fit) continue;
        auto instance = instance_of(fit->model);
        if (!instance) continue;
        if (instance->kind == Instance::Kind::kPlane) orient_to_sensor(*instance, free);
        auto inliers = largest_piece(*instance, free);
        if (instance->kind == Instance::Kind::kConvexCylinder) {
          if (auto ball = ball_around(*instance, inliers)) {
            auto cap = largest_piece(*ball, free);
            if (covers_a_cap(*ball, cap) && refit_ball(*ball, cap, seed + 1)) {
              cap = largest_piece(*ball, free);
              if (covers_a_cap(*ball, cap)) offer(std::move(*ball), std::move(cap));
            }
          }
          if (!covers_an_arc(*instance, inliers)) continue;
        }
        offer(std::move(*instance), std::move(inliers));
      }
      if (!best || best_inliers.size() < options_.min_instance_points) break;
      const std::uint32_t id = std::uint32_t(instances_.size());
      for (std::uint32_t k : best_inliers) owner_[k] = id;
      if (best->convex_solid() && !seen_from_outside(*best, best_inliers))
        best->kind = Instance::Kind::kNoSolid;
      best->inliers = std::move(best_inliers);
      instances_.push_back(std::move(*best));
      std::erase_if(free, [&](std::uint32_t k) { return owner_[k] != kNone; });
    }
  }

  // The inliers around a cylinder's axis: each one's angle (sorted, with its cluster-local id) and
  // the arc they cover, from `first` over `span`: the complement of the widest empty gap.
  struct Arc {
    std::vector<std::pair<double, std::uint32_t>> by_angle;
    double first = 0, span = 0;
  };
  Arc arc_around(const Instance& cylinder, const std::vector<std::uint32_t>& inliers) const {
    Arc arc;
    const Vec3d u = cylinder.axis.unitOrthogonal(), v = cylinder.axis.cross(u);
    arc.by_angle.reserve(inliers.size());
    for (std::uint32_t k : inliers) {
      const Vec3d q = point(k) - cylinder.axis_point;
      arc.by_angle.emplace_back(std::atan2(q.dot(v), q.dot(u)), k);
    }
    std::sort(arc.by_angle.begin(), arc.by_angle.end());
    const auto& a = arc.by_angle;
    std::size_t start = 0;
    double widest = a.front().first + 2 * M_PI - a.back().first;
    for (std::size_t k = 1; k < a.size(); ++k)
      if (a[k].first - a[k - 1].first > widest) {
        widest = a[k].first - a[k - 1].first;
        start = k;
      }
    arc.first = a[start].first, arc.span = 2 * M_PI - widest;
    return arc;
  }

  // A box's rounded edge fitted as a can: beyond one end of its arc the surface runs on as a flat
  // face tangent to the cylinder (its plane at the radius, the axis behind it, its normal across
  // the axis) that then leaves the cylinder. A can's arc ends at its silhouette (nothing of the
  // cluster beyond), at its lid (a normal along the axis), or at another object (whose face has
  // the can in front of it); a can's rim stays on its cylinder.
  bool rounded_box_edge(const Instance& cylinder) const {
    constexpr double kEndSpan = 10.0 * kDegree;  // the arc's end: inliers this close to it
    constexpr int kPixelsOn = 8;                 // how far on from the end the face is read
    constexpr std::size_t kLeastFace = 20;
    constexpr double kFlatShare = 0.7, kLeavingShare = 0.3, kRadiusTolerance = 0.25;
    const std::vector<std::uint32_t>& inliers = cylinder.inliers;
    if (inliers.empty()) return false;
    const auto [by_angle, first, span] = arc_around(cylinder, inliers);
    std::vector<std::uint8_t> steps(cluster_->size(), 0);  // 0: not reached; else pixels on + 1
    for (std::uint32_t k : inliers) steps[k] = 1;
    for (int end = 0; end < 2; ++end) {
      std::vector<std::uint32_t> queue, face;
      std::vector<std::uint8_t> reached(steps);
      for (const auto& [angle, k] : by_angle) {
        const double along = std::fmod(angle - first + 2 * M_PI, 2 * M_PI);
        if (end == 0 ? along <= kEndSpan : along >= span - kEndSpan) queue.push_back(k);
      }
      for (std::size_t q = 0; q < queue.size(); ++q) {
        const std::uint32_t k = queue[q];
        if (reached[k] > kPixelsOn) continue;
        for_each_touching(k, [&](std::uint32_t j) {
          if (reached[j]) return;
          reached[j] = std::uint8_t(reached[k] + 1);
          queue.push_back(j);
          if (normals_[global(j)].allFinite()) face.push_back(j);
        });
      }
      if (face.size() < kLeastFace) continue;
      Vec3d normal = Vec3d::Zero(), centre = Vec3d::Zero();
      for (std::uint32_t k : face) {
        normal += normals_[global(k)].cast<double>();
        centre += point(k);
      }
      centre /= double(face.size());
      if (!(normal.norm() > 0)) continue;
      normal.normalize();
      std::size_t flat = 0, leaving = 0;
      for (std::uint32_t k : face) {
        flat += std::abs(normal.dot(point(k) - centre)) <= band_;
        leaving += cylinder.in_front(point(k)) > band_;
      }
      const double axis_behind = normal.dot(centre - cylinder.axis_point);
      if (double(flat) >= kFlatShare * double(face.size()) &&
          double(leaving) >= kLeavingShare * double(face.size()) &&
          std::abs(normal.dot(cylinder.axis)) <= std::sin(options_.normal_angle_deg * kDegree) &&
          axis_behind > 0 &&
          std::abs(axis_behind - cylinder.radius) <=
              std::max(2 * band_, kRadiusTolerance * cylinder.radius))
        return true;
    }
    return false;
  }

  // A can's side is seen as one unbroken arc around its axis. A cylinder through strips of two
  // faces of a box (within the band where it crosses them) leaves the arc between them empty.
  bool covers_an_arc(const Instance& cylinder, const std::vector<std::uint32_t>& inliers) const {
    constexpr double kBin = 10.0 * kDegree, kMinSpan = 90.0 * kDegree;
    if (inliers.empty()) return false;
    const auto [by_angle, first, span] = arc_around(cylinder, inliers);
    if (span < kMinSpan) return false;
    const std::size_t bins = std::size_t(std::ceil(span / kBin));
    std::vector<std::size_t> count(bins, 0);
    for (const auto& [a, k] : by_angle) {
      double offset = a - first;
      if (offset < 0) offset += 2 * M_PI;
      ++count[std::min(bins - 1, std::size_t(offset / kBin))];
    }
    const double expected = double(by_angle.size()) / double(bins);
    const auto filled = std::count_if(count.begin(), count.end(),
                                      [&](std::size_t c) { return double(c) >= 0.25 * expected; });
    return double(filled) >= 0.8 * double(bins);
  }

  // A cylinder fitted to a ball takes a band around it, no wider along its axis than where the
  // ball's normals stay within normal_angle_deg of the cylinder's (plus the band either side),
  // and centred on it: the sphere of the cylinder's radius centred there is nearly the ball's
  // (the band's radius a little short of the ball's), to be grown over the free points and
  // refitted when it covers a cap. Fitting a sphere to every round's free points instead cost
  // 11% more instructions on crowded c13, and fitting one to every such band 4% on mOSD learn36.
  std::optional<Instance> ball_around(const Instance& cylinder,
                                      const std::vector<std::uint32_t>& strip) const {
    if (strip.size() < options_.min_instance_points) return std::nullopt;
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (std::uint32_t k : strip) {
      const double along = (point(k) - cylinder.axis_point).dot(cylinder.axis);
      low = std::min(low, along);
      high = std::max(high, along);
    }
    if (high - low >
        2 * cylinder.radius * std::sin(options_.normal_angle_deg * kDegree) + 2 * band_)
      return std::nullopt;
    Instance ball;
    ball.kind = Instance::Kind::kConvexSphere;
    ball.sphere = true;
    ball.axis_point = cylinder.axis_point + 0.5 * (low + high) * cylinder.axis;
    ball.radius = cylinder.radius;
    return ball;
  }

  // The sphere fitted to a ball's cap (object-sized); false when there is none.
  bool refit_ball(Instance& ball, const std::vector<std::uint32_t>& cap, std::uint64_t seed) const {
    std::vector<std::uint32_t> indices(cap.size());
    for (std::size_t k = 0; k < cap.size(); ++k) indices[k] = global(cap[k]);
    const auto fit =
        primitives::fit_model(primitives::PrimitiveKind::kSphere, {xyz_, normals_, indices},
                              fit_settings(primitives::PrimitiveKind::kSphere), seed);
    if (!fit) return false;
    const auto& sphere = std::get<primitives::SphereModel>(fit->model);
    ball.axis_point = sphere.center;
    ball.radius = sphere.radius;
    return true;
  }

  // A ball is seen as a cap reaching far from its middle in every direction. Where an inlier's
  // normal agrees with a sphere's only within normal_angle_deg, a sphere through a surface
  // curved one way (a can's side, a rounded edge: strips of a cylinder) or not at all (a plane's
  // gentle bulge) reaches no farther than that angle across it; a corner rounded into a sphere
  // is an eighth of it, reaching 35 degrees towards its edges. The cap's middle is the inliers'
  // mean direction from the centre; each of 8 sectors around it holds inliers at least 45
  // degrees out (one may be hidden: a neighbour in front, the contact).
  bool covers_a_cap(const Instance& sphere, const std::vector<std::uint32_t>& inliers) const {
    constexpr int kSectors = 8;
    const double reach = std::cos(45.0 * kDegree);
    if (inliers.empty()) return false;
    std::vector<Vec3d> direction;
    direction.reserve(inliers.size());
    Vec3d middle = Vec3d::Zero();
    for (std::uint32_t k : inliers) {
      direction.push_back((point(k) - sphere.axis_point).normalized());
      middle += direction.back();
    }
    if (!(middle.norm() > 0)) return false;
    middle.normalize();
    const Vec3d u = middle.unitOrthogonal(), v = middle.cross(u);
    std::array<std::size_t, kSectors> far{};
    for (const Vec3d& d : direction) {
      if (d.dot(middle) > reach) continue;
      const double angle = std::atan2(d.dot(v), d.dot(u)) + M_PI;  // [0, 2 pi]
      ++far[std::min(kSectors - 1, int(angle / (2 * M_PI / kSectors)))];
    }
    // A sector counts with an eighth of an even share of the inliers out there.
    const double least = double(inliers.size()) / (kSectors * kSectors);
    const auto filled = std::count_if(far.begin(), far.end(),
                                      [&](std::size_t c) { return c > 0 && double(c) >= least; });
    return filled >= kSectors - 1;
  }

  // A plane's front is the side its points' normals face (the sensor's side).
  void orient_to_sensor(Instance& plane, const std::vector<std::uint32_t>& free) const {
    double facing = 0;
    for (std::uint32_t k : free)
      if (std::abs(plane.in_front(point(k))) <= band_)
        facing += plane.normal.dot(normals_[global(k)].cast<double>());
    if (facing < 0) {
      plane.normal = -plane.normal;
      plane.offset = -plane.offset;
    }
  }

  // A can or a ball seen from outside: its points' normals (facing the sensor) point away from
  // the axis or the centre; the inside of a mug's wall or of a bowl faces them and bounds no solid
  // this test could use.
  bool seen_from_outside(const Instance& curved, const std::vector<std::uint32_t>& inliers) const {
    std::size_t outward = 0;
    for (std::uint32_t k : inliers)
      if (curved.radial(point(k)).dot(normals_[global(k)].cast<double>()) > 0) ++outward;
    return 2 * outward > inliers.size();
  }

  // Points no instance took join the instance they touch in the image, nearest first; pieces
  // touching none become instances without a solid.
  void assign_the_rest() {
    std::deque<std::uint32_t> queue;
    for (std::uint32_t k = 0; k < cluster_->size(); ++k)
      if (owner_[k] != kNone) queue.push_back(k);
    while (!queue.empty()) {
      const std::uint32_t k = queue.front();
      queue.pop_front();
      for_each_touching(k, [&](std::uint32_t j) {
        if (owner_[j] == kNone) {
          owner_[j] = owner_[k];
          queue.push_back(j);
        }
      });
    }
    for (std::uint32_t k = 0; k < cluster_->size(); ++k) {
      if (owner_[k] != kNone) continue;
      const std::uint32_t id = std::uint32_t(instances_.size());
      instances_.emplace_back();
      owner_[k] = id;
      queue.push_back(k);
      while (!queue.empty()) {
        const std::uint32_t q = queue.front();
        queue.pop_front();
        for_each_touching(q, [&](std::uint32_t j) {
          if (owner_[j] == kNone) {
            owner_[j] = id;
            queue.push_back(j);
          }
        });
      }
    }
  }

  // Whether the surface at `local` runs on from `can`'s: its normal (its plane's, when a plane
  // took it, which is steadier than a point's) along the can's outward radial direction. A box's
  // face that a can touches faces the other way.
  bool continues(const Instance& can, std::uint32_t local) const {
    const Instance& owner = instances_[owner_[local]];
    Vec3d normal;
    if (owner.kind == Instance::Kind::kPlane) {
      normal = owner.normal;
    } else {
      const Vec3f& nf = normals_[global(local)];
      if (!nf.allFinite()) return false;
      normal = nf.cast<double>();
    }
    return can.radial(point(local)).normalized().dot(normal) >=
           std::cos(options_.normal_angle_deg * kDegree);
  }

  // Share of a's inliers outside b's solid (in front of its surface) by more than the band.
  double share_in_front(const Instance& a, const Instance& b) const {
    if (a.inliers.empty()) return 0.0;
    std::size_t in_front = 0;
    for (std::uint32_t k : a.inliers)
      if (b.in_front(point(k)) > band_) ++in_front;
    return double(in_front) / double(a.inliers.size());
  }

  // Whether x reaches farther from the can's axis than the can's own diameter: a handle or a
  // spout stays closer to the wall than the can is wide; a neighbour object reaches beyond.
  bool reaches_beyond(const Instance& x, const Instance& can) const {
    std::size_t beyond = 0;
    for (std::uint32_t k : x.inliers)
      if (can.radial(point(k)).norm() > 2 * can.radius) ++beyond;
    return beyond * 20 >= x.inliers.size();  // 5%: more than noise at its far end
  }

  // A can's surface bounds its solid all round, so what touches it from outside is another
  // object: a box's face or top beside it, the top it stands on, another can. A plane bounds only
  // a half-space that a neighbour's visible part may well lie in (a can beside a box is below
  // the box's top), and planes meeting at concave creases are the crease split's.
  bool separate(std::uint32_t a, std::uint32_t b) const {
    using Kind = Instance::Kind;
    const auto outside_can = [&](std::uint32_t x, std::uint32_t can) {
      const Instance &other = instances_[x], &solid = instances_[can];
      return solid.convex_solid() && solid.inliers.size() >= options_.min_object_points &&
             (other.kind == Kind::kPlane || other.convex_solid()) &&
             !continuing_.contains({can, x}) &&
             share_in_front(other, solid) > options_.outside_share && reaches_beyond(other, solid);
    };
    return outside_can(a, b) || outside_can(b, a);
  }

  // A plane through a can's lid and the top of a box of its height is one fitted instance; the
  // can's solid cuts it into the lid (inside the radius, at the can's end) and the rest.
  void cut_planes_by_cans() {
    const std::size_t fitted = instances_.size();
    for (std::size_t c = 0; c < fitted; ++c) {
      if (instances_[c].kind != Instance::Kind::kConvexCylinder) continue;
      const Instance& can = instances_[c];
      double low = std::numeric_limits<double>::infinity(), high = -low;
      for (std::uint32_t k : can.inliers) {
        const double along = (point(k) - can.axis_point).dot(can.axis);
        low = std::min(low, along);
        high = std::max(high, along);
      }
      for (std::size_t p = 0; p < fitted; ++p) {
        if (instances_[p].kind != Instance::Kind::kPlane) continue;
        std::vector<std::uint32_t> inside, outside;
        for (std::uint32_t k : instances_[p].inliers) {
          const Vec3d q = point(k) - instances_[c].axis_point;
          const double along = q.dot(instances_[c].axis);
          const bool within = along >= low - band_ && along <= high + band_ &&
                              instances_[c].in_front(point(k)) <= band_;
          (within ? inside : outside).push_back(k);
        }
        if (inside.size() < options_.min_instance_points / 2 ||
            outside.size() < options_.min_instance_points / 2)
          continue;
        Instance lid = instances_[p];
        lid.inliers = std::move(inside);
        instances_[p].inliers = std::move(outside);
        const std::uint32_t id = std::uint32_t(instances_.size());
        for (std::uint32_t k : lid.inliers) owner_[k] = id;
        instances_.push_back(std::move(lid));
      }
    }
  }

  bool upright(const Instance& instance) const {
    const double sine = std::sin(options_.upright_deg * kDegree);
    if (instance.kind == Instance::Kind::kPlane) return std::abs(instance.normal.dot(up_)) <= sine;
    if (instance.kind == Instance::Kind::kConvexCylinder)
      return std::abs(instance.axis.dot(up_)) >= std::cos(options_.upright_deg * kDegree);
    return false;
  }

  colour::TwoColourRule colour_rule() const {
    colour::TwoColourRule rule;
    rule.explained = options_.seam_explained;
    rule.step = options_.seam_chromaticity_step;
    rule.separation = options_.material_separation;
    rule.least = options_.min_instance_points / 2;
    return rule;
  }

  // Two objects of one footprint stacked share their side faces' instances: every upright
  // instance whose colour steps at one height (within the band) is cut there, and no piece below
  // the seam may join one above it.
  void cut_at_colour_seams() {
    std::vector<std::pair<std::size_t, double>> seams;  // instance, height; largest first
    for (std::size_t i = 0; i < instances_.size(); ++i) {
      if (!upright(instances_[i])) continue;
      std::vector<std::pair<double, Eigen::Vector2d>> samples;
      for (std::uint32_t k : instances_[i].inliers)
        if (const auto c = colour::chromaticity(rgba_[global(k)]))
          samples.emplace_back(height_of_[global(k)], *c);
      if (const auto seam =
              colour::height_step(std::move(samples), options_.seam_min_rise, colour_rule()))
        seams.emplace_back(i, *seam);
    }
    std::stable_sort(seams.begin(), seams.end(), [&](const auto& a, const auto& b) {
      return instances_[a.first].inliers.size() > instances_[b.first].inliers.size();
    });
    std::vector<bool> done(seams.size(), false);
    for (std::size_t s = 0; s < seams.size(); ++s) {
      if (done[s]) continue;
      const double at_height = seams[s].second;
      std::vector<std::uint32_t> below, above;
      for (std::size_t t = s; t < seams.size(); ++t) {
        if (done[t] || std::abs(seams[t].second - at_height) > band_) continue;
        done[t] = true;
        Instance& instance = instances_[seams[t].first];
        Instance upper = instance;
        upper.inliers.clear();
        std::vector<std::uint32_t> lower;
        for (std::uint32_t k : instance.inliers)
          (height_of_[global(k)] > at_height ? upper.inliers : lower).push_back(k);
        instance.inliers = std::move(lower);
        const std::uint32_t id = std::uint32_t(instances_.size());
        for (std::uint32_t k : upper.inliers) owner_[k] = id;
        below.push_back(std::uint32_t(seams[t].first));
        above.push_back(id);
        instances_.push_back(std::move(upper));
      }
      // The other instances lying wholly below or above the seam (the lower box's face the upper
      // one hides, the upper box's top) take their side too.
      const std::size_t cut_end = instances_.size();
      for (std::size_t i = 0; i < cut_end; ++i) {
        const auto& inliers = instances_[i].inliers;
        if (inliers.empty() || std::count(below.begin(), below.end(), i) ||
            std::count(above.begin(), above.end(), i))
          continue;
        const auto [low, high] = std::minmax_element(
            inliers.begin(), inliers.end(), [&](std::uint32_t a, std::uint32_t b) {
              return height_of_[global(a)] < height_of_[global(b)];
            });
        if (height_of_[global(*high)] <= at_height + band_)
          below.push_back(std::uint32_t(i));
        else if (height_of_[global(*low)] >= at_height - band_)
          above.push_back(std::uint32_t(i));
      }
      for (std::uint32_t a : below)
        for (std::uint32_t b : above) colour_apart_.emplace_back(a, b);
    }
  }

  // A fitted surface through two objects of different even colours (a box's top in the plane of
  // the book leaning on it) is two surfaces, which never join.
  void cut_mixed_materials() {
    const std::size_t fitted = instances_.size();
    for (std::size_t i = 0; i < fitted; ++i) {
      Instance& instance = instances_[i];
      if (instance.kind == Instance::Kind::kNoSolid) continue;
      std::vector<std::uint32_t> counted;
      std::vector<Eigen::Vector2d> colours;
      for (std::uint32_t k : instance.inliers)
        if (const auto c = colour::chromaticity(rgba_[global(k)])) {
          counted.push_back(k);
          colours.push_back(*c);
        }
      const auto group = colour::two_materials(colours, colour_rule());
      if (!group) continue;
      // Pixels too dark to tell stay with the first group; the second becomes an instance.
      Instance second = instance;
      second.inliers.clear();
      for (std::size_t k = 0; k < counted.size(); ++k)
        if ((*group)[k]) second.inliers.push_back(counted[k]);
      std::vector<std::uint32_t> first;
      std::set_difference(instance.inliers.begin(), instance.inliers.end(), second.inliers.begin(),
                          second.inliers.end(), std::back_inserter(first));
      instance.inliers = std::move(first);
      const std::uint32_t id = std::uint32_t(instances_.size());
      for (std::uint32_t k : second.inliers) owner_[k] = id;
      colour_apart_.emplace_back(std::uint32_t(i), id);
      instances_.push_back(std::move(second));
    }
  }

  bool colour_known() const { return options_.use_colour && !rgba_.empty(); }

  // Per instance: its material; none for instances without a solid or too small to tell, or
  // without colour.
  std::vector<colour::Material> instance_materials() const {
    std::vector<colour::Material> materials(instances_.size());
    if (!colour_known()) return materials;
    for (std::size_t i = 0; i < instances_.size(); ++i) {
      if (instances_[i].kind == Instance::Kind::kNoSolid) continue;
      std::vector<Eigen::Vector2d> colours;
      for (std::uint32_t k : instances_[i].inliers)
        if (const auto c = colour::chromaticity(rgba_[global(k)])) colours.push_back(*c);
      materials[i] = colour::material_of(colours, options_.min_object_points / 2);
    }
    return materials;
  }

  struct PieceStats {
    std::size_t size = 0;
  };

  // Per piece (by root): its size.
  std::map<std::uint32_t, PieceStats> piece_stats(DisjointSets& objects) const {
    std::map<std::uint32_t, PieceStats> stats;
    for (std::uint32_t k = 0; k < cluster_->size(); ++k) ++stats[objects.find(owner_[k])].size;
    return stats;
  }

  // Joins pieces for which must_join(root, stats) holds to the piece they touch most (or, touching
  // none, the largest), smallest first, until none is left or one piece remains.
  template <typename MustJoin>
  void absorb(DisjointSets& objects,
              const std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t>& contact,
              MustJoin&& must_join) {
    for (;;) {
      stats_ = piece_stats(objects);
      if (stats_.size() < 2) return;
      std::uint32_t chosen = kNone;
      for (const auto& [root, piece] : stats_)
        if (must_join(root, piece) && (chosen == kNone || piece.size < stats_[chosen].size))
          chosen = root;
      if (chosen == kNone) return;
      std::map<std::uint32_t, std::size_t> touch;
      for (const auto& [pair, count] : contact) {
        const std::uint32_t a = objects.find(pair.first), b = objects.find(pair.second);
        if (a == b) continue;
        if (a == chosen) touch[b] += count;
        if (b == chosen) touch[a] += count;
      }
      std::uint32_t best = kNone;
      for (const auto& [other, count] : touch)
        if (best == kNone || count > touch[best]) best = other;
      if (best == kNone)
        for (const auto& [root, piece] : stats_)
          if (root != chosen && (best == kNone || piece.size > stats_[best].size)) best = root;
      objects.join(chosen, best);
    }
  }

  std::vector<std::vector<std::uint32_t>> join_instances() {
    const std::uint32_t n = std::uint32_t(instances_.size());
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> contact;
    // Per (can, neighbour): their contacts, and those where the neighbour's surface runs on
    // from the can's (the wider top of a tapered cup, a bottle's shoulder).
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<std::size_t, std::size_t>> runs_on;
    for (std::uint32_t k = 0; k < cluster_->size(); ++k)
      for_each_touching(k, [&](std::uint32_t j) {
        const std::uint32_t a = owner_[k], b = owner_[j];
        if (a == b) return;
        if (k < j) ++contact[{std::min(a, b), std::max(a, b)}];
        if (instances_[a].convex_solid()) {
          auto& [touching, smooth] = runs_on[{a, b}];
          ++touching;
          if (continues(instances_[a], j)) ++smooth;
        }
      });
    continuing_.clear();
    for (const auto& [pair, counts] : runs_on)
      if (double(counts.second) > options_.outside_share * double(counts.first))
        continuing_.insert(pair);
    DisjointSets objects(n);
    // What lies outside a can is never joined to it, even through a third instance (the lid of a
    // can beside a box of its height touches the box's top): joins go by contact length, longest
    // first, each only when no can and an instance outside it would end up together.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> apart = colour_apart_;
    const auto materials = instance_materials();
    const colour::TwoColourRule rule = colour_rule();
    for (std::uint32_t a = 0; a < n; ++a)
      for (std::uint32_t b = a + 1; b < n; ++b)
        if (separate(a, b) || colour::different(materials[a], materials[b], rule))
          apart.emplace_back(a, b);
    std::vector<std::pair<std::pair<std::uint32_t, std::uint32_t>, std::size_t>> joins(
        contact.begin(), contact.end());
    // Surfaces of one even material join first: the top of a box that a book leans on belongs
    // with the box's sides even where it touches the book along more pixels.
    const auto same = [&](const auto& join) {
      return colour::same(materials[join.first.first], materials[join.first.second], rule);
    };
    std::stable_sort(joins.begin(), joins.end(), [&](const auto& x, const auto& y) {
      const bool sx = same(x), sy = same(y);
      return sx != sy ? sx : x.second > y.second;
    });
    for (const auto& [pair, count] : joins) {
      const std::uint32_t a = objects.find(pair.first), b = objects.find(pair.second);
      if (a == b) continue;
      const bool kept_apart = std::any_of(apart.begin(), apart.end(), [&](const auto& x) {
        const std::uint32_t u = objects.find(x.first), v = objects.find(x.second);
        return (u == a && v == b) || (u == b && v == a);
      });
      if (!kept_apart) objects.join(a, b);
    }

    // Pieces too small to be objects, then pieces with no fitted surface of their own (a pot's
    // handle, outside the pot's wall), join the piece they touch most, smallest first.
    absorb(objects, contact, [&](std::uint32_t, const PieceStats& piece) {
      return piece.size < options_.min_object_points;
    });
    absorb(objects, contact, [&](std::uint32_t root, const PieceStats&) {
      for (std::uint32_t i = 0; i < n; ++i)
        if (objects.find(i) == root && instances_[i].kind != Instance::Kind::kNoSolid &&
            2 * instances_[i].inliers.size() >= options_.min_object_points)
          return false;
      return true;
    });

    std::map<std::uint32_t, std::vector<std::uint32_t>> pieces;
    for (std::uint32_t k = 0; k < cluster_->size(); ++k)
      pieces[objects.find(owner_[k])].push_back(global(k));
    std::vector<std::vector<std::uint32_t>> out;
    for (auto& [root, members] : pieces) {
      std::sort(members.begin(), members.end());
      out.push_back(std::move(members));
    }
    return out;
  }

  const std::vector<Vec3f>& xyz_;
  const std::vector<std::uint32_t>& rgba_;
  const std::vector<float>& height_of_;  // per input point: above the table
  Vec3d up_;
  int width_, height_;
  Vec3f viewpoint_;
  const ShapeSplitOptions& options_;
  std::vector<std::uint32_t> local_;  // per input point: cluster-local id, kNone outside
  std::vector<Vec3f> normals_;        // per input point: grid normal, NaN when none
  const std::vector<std::uint32_t>* cluster_ = nullptr;
  double band_ = 0;
  std::vector<Instance> instances_;
  std::vector<std::uint32_t> owner_;                              // per cluster point: its instance
  std::map<std::uint32_t, PieceStats> stats_;                     // per piece while joining
  std::set<std::pair<std::uint32_t, std::uint32_t>> continuing_;  // (can, neighbour) running on
  std::vector<std::pair<std::uint32_t, std::uint32_t>> colour_apart_;  // instances colour parts
  std::vector<std::uint8_t> mark_;
  std::vector<KeptApart::Solid> solids_;
};

}  // namespace

std::vector<std::vector<std::uint32_t>> split_by_shape(
    const PointCloud& cloud, const std::vector<float>& height, const Vec3f& up,
    std::vector<std::vector<std::uint32_t>> clusters, const ShapeSplitOptions& options,
    KeptApart* kept_apart, const RunContext& context) {
  options.validate();
  if (kept_apart) *kept_apart = {};
  std::vector<std::vector<std::uint32_t>> out;
  if (!options.enabled || !cloud.organized()) {
    out = std::move(clusters);
  } else {
    if (height.size() != cloud.size())
      throw std::invalid_argument("shape split needs a height above the table for every point");
    // Clusters are independent: one splitter (with its image-sized buffers) per thread, the
    // pieces gathered in cluster order, so the result is the same for any thread count.
    std::vector<std::vector<std::vector<std::uint32_t>>> split(clusters.size());
    std::vector<std::vector<KeptApart::Solid>> solids(clusters.size());
    detail::parallel_for(
        std::ptrdiff_t(clusters.size()), context.threads, detail::Schedule::Dynamic(1),
        [&] { return std::make_unique<ShapeSplitter>(cloud, height, up, options); },
        [&](std::unique_ptr<ShapeSplitter>& splitter, std::ptrdiff_t c) {
          if (clusters[c].empty() || context.stopped()) return;
          split[c] = splitter->split(clusters[c]);
          solids[c] = splitter->solids();
        });
    context.throw_if_stopped("table-top shape split");
    for (std::uint32_t c = 0; c < clusters.size(); ++c) {
      auto& pieces = split[c];
      if (kept_apart && pieces.size() > 1) {
        if (kept_apart->piece.empty()) kept_apart->piece.assign(cloud.size(), -1);
        for (const auto& piece : pieces) {
          for (std::uint32_t i : piece)
            kept_apart->piece[i] = std::int32_t(kept_apart->origin.size());
          kept_apart->origin.push_back(c);
        }
      }
      for (auto& piece : pieces) out.push_back(std::move(piece));
      if (kept_apart)
        kept_apart->solids.insert(kept_apart->solids.end(), solids[c].begin(), solids[c].end());
    }
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  return out;
}

}  // namespace primlabel::tabletop
