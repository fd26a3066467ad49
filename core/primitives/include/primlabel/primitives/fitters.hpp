#pragma once
// One segment's points fitted with one parametric model: MSAC (truncated quadratic cost, Torr &
// Zisserman) over hypotheses from minimal samples drawn by a seeded generator, then least squares
// on the inliers (Levenberg-Marquardt for the curved models). Cylinders and spheres are
// hypothesised from two points and their normals, tori from the normal lines (every normal of a
// surface of revolution meets its axis); planes and lines need no normals. A fit depends only on
// its points and seed, never on threads.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/primitives/primitive.hpp"

namespace primlabel::primitives {

struct FitSettings {
  double distance_threshold = 0.003;      // inlier band half-width (m)
  double normal_angle_deg = 30;           // an inlier's normal (when it has one) within this of the
                                          // model's surface normal, either sign
  int hypotheses = 200;                   // MSAC samples drawn
  std::size_t max_scoring_points = 1000;  // hypotheses are scored on an evenly strided subset
  std::size_t max_refine_points = 20000;  // least squares runs on at most this many inliers
  int refine_iterations = 20;
  double min_radius = 0.002, max_radius = 2.0;  // cylinders, spheres, tori (major radius)
  // fit_model reports a cylinder, sphere or torus only when its description length (BIC on the
  // band-truncated residuals, explains_better_than_simpler) beats every simpler surface fitted
  // to the same points: a plane; for a torus also a cylinder and a sphere.
  bool prefer_simpler = true;

  void validate() const;  // throws std::invalid_argument naming the bad setting
};

// The points of one segment: xyz[indices[k]], with normals[indices[k]] when `normals` is not
// empty (NaN entries: no normal). Non-finite points are skipped.
struct SegmentPoints {
  std::span<const Vec3f> xyz;
  std::span<const Vec3f> normals;
  std::span<const std::uint32_t> indices;
};

struct Fit {
  Model model;
  std::size_t inliers = 0;
  double rms = 0;
  double confidence = 0;
};

// Nothing when too few usable points (or normals, for cylinders, spheres, tori) or no hypothesis
// within the radius bounds.
std::optional<Fit> fit_plane(const SegmentPoints& points, const FitSettings& settings,
                             std::uint64_t seed);
std::optional<Fit> fit_cylinder(const SegmentPoints& points, const FitSettings& settings,
                                std::uint64_t seed);
std::optional<Fit> fit_sphere(const SegmentPoints& points, const FitSettings& settings,
                              std::uint64_t seed);
std::optional<Fit> fit_torus(const SegmentPoints& points, const FitSettings& settings,
                             std::uint64_t seed);
// An edge band: the crease where its two dominant planes meet, clipped to the points' extent
// along it; a band with one plane only (a curved edge) gets that plane's principal in-plane axis
// and half the confidence.
std::optional<Fit> fit_line(const SegmentPoints& points, const FitSettings& settings,
                            std::uint64_t seed);

// Whether `fit` (of `kind`: cylinder, sphere or torus; any other kind is always true) has a
// lower description length on `points` than each simpler surface fitted to them with the same
// seed: n ln(S / n) + k ln n (BIC with the noise variance unknown), S the squared distances
// truncated at the inlier band (MSAC's cost: a point outside it, or with a disagreeing normal,
// costs the band's square), k the surface's parameters (plane 3, sphere 4, cylinder 5, torus
// 7). No constant to tune: the band is the fit's own and the penalty is BIC's (residuals under a
// thousandth of the band count as that, so noise-free points do not give ln 0).
bool explains_better_than_simpler(PrimitiveKind kind, const Fit& fit, const SegmentPoints& points,
                                  const FitSettings& settings, std::uint64_t seed);

// Dispatches on `kind` (kSegment: nothing); with settings.prefer_simpler, nothing for a curved
// fit a simpler surface describes as well (explains_better_than_simpler).
std::optional<Fit> fit_model(PrimitiveKind kind, const SegmentPoints& points,
                             const FitSettings& settings, std::uint64_t seed);

}  // namespace primlabel::primitives
