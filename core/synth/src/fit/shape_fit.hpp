#pragma once
// The pieces of the fitted ground truth (synth/fitted_truth.hpp), in the truth frame (z up, table z = 0).

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <vector>

#include "primlabel/synth/fitted_truth.hpp"
#include "primlabel/synth/shapes.hpp"

namespace primlabel::synth::fit {

using Vec3d = Eigen::Vector3d;

// One segment's points in the truth frame, their normals (NaN where none) and residual bounds.
struct SegmentPoints {
  std::vector<Vec3d> p, n;
  std::vector<double> bound;
  std::vector<double> depth;        // along the sensor's view axis (m)
  Vec3d viewpoint = Vec3d::Zero();  // the sensor, so faces can be oriented toward it
};

struct FitSettings {
  double contact_tolerance = 0.02;
  std::uint64_t seed = 1;
};

// The closest point of a fitted object's closed surface to `local` (its local frame), its part
// (numbered as the synth shape's), distance and the surface normal there (out of the material).
// With the point's normal (NaN: none), the closest part that normal supports, when there is one.
struct SurfacePoint {
  int part = -1;
  Vec3d point = Vec3d::Zero();
  double distance = 0;
  Vec3d normal = Vec3d::Zero();
};

// A point supports a surface when it lies within its bound and its normal (when it has one)
// is within 60 degrees of the surface's: generous for normals blurred across a crease, but the
// inside of a vessel (normals toward the axis) is no evidence for a solid.
inline bool supports(double distance, double bound, const Vec3d& point_normal,
                     const Vec3d& surface_normal) {
  return distance < bound && !(point_normal.dot(surface_normal) < 0.5);
}
SurfacePoint closest_surface(const FittedObject& object, const Vec3d& local,
                             const Vec3d& normal = Vec3d::Constant(NAN));

// The synthetic shape of a fitted object (BoxShape, CanShape, LyingCanShape).
std::shared_ptr<const synth::Shape> make_shape(const FittedObject& object);

struct Evidence {
  double cost = 1;  // mean of min(d², bound²) / bound², 1 for a point that does not support it
  std::size_t inliers = 0;
  double rms = 0;
};
Evidence evaluate(const FittedObject& object, const SegmentPoints& segment);

std::optional<FittedObject> fit_box(const SegmentPoints& segment, const FitSettings& settings);
std::optional<FittedObject> fit_cylinder(const SegmentPoints& segment, const FitSettings& settings);

// Value at quantile q in [0, 1] (nearest rank) of `values` (copied).
double quantile(std::vector<double> values, double q);

// A point on a fitted surface, to be labeled by the synthetic rule: scene object index (0 the
// table), part and the closest surface point in the truth frame.
struct RulePoint {
  int object = 0;
  int part = -1;
  Vec3d surface = Vec3d::Zero();
};
// synth::ground_truth at `radius` for every point, then the observed-crease rule over them.
std::vector<std::uint32_t> label_by_rule(const synth::Scene& scene,
                                         const std::vector<RulePoint>& points, double radius);

}  // namespace primlabel::synth::fit
