#include "primlabel/primitives/fitters.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace primlabel::primitives {

void FitSettings::validate() const {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("primitive fit: " + what);
  };
  if (!(distance_threshold > 0) || !std::isfinite(distance_threshold))
    fail("distance threshold must be finite and > 0");
  if (!(normal_angle_deg > 0 && normal_angle_deg <= 90)) fail("normal angle must be in (0, 90]");
  if (hypotheses < 1 || hypotheses > 100000) fail("hypotheses must be in [1, 100000]");
  if (max_scoring_points < 10 || max_refine_points < 10)
    fail("scoring and refinement points must be at least 10");
  if (refine_iterations < 0 || refine_iterations > 1000)
    fail("refine iterations must be in [0, 1000]");
  if (!(min_radius >= 0 && min_radius < max_radius) || !std::isfinite(max_radius))
    fail("radius bounds must be finite with 0 <= min < max");
}

std::optional<Fit> fit_model(PrimitiveKind kind, const SegmentPoints& points,
                             const FitSettings& settings, std::uint64_t seed) {
  switch (kind) {
    case PrimitiveKind::kPlane:
      return fit_plane(points, settings, seed);
    case PrimitiveKind::kCylinder:
      return fit_cylinder(points, settings, seed);
    case PrimitiveKind::kSphere:
      return fit_sphere(points, settings, seed);
    case PrimitiveKind::kTorus:
      return fit_torus(points, settings, seed);
    case PrimitiveKind::kLine:
      return fit_line(points, settings, seed);
    case PrimitiveKind::kSegment:
      break;
  }
  return std::nullopt;
}

}  // namespace primlabel::primitives
