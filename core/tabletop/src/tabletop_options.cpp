#include <cmath>
#include <stdexcept>
#include <string>

#include "primlabel/tabletop/tabletop.hpp"

namespace primlabel::tabletop {

void TabletopOptions::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (up_source == UpAxisSource::kGiven && (!is_finite(up) || up.norm() < 1e-6f))
    fail("the given up axis must be a finite non-zero vector");
  if (!(max_tilt_deg > 0.0f && max_tilt_deg <= 90.0f))
    fail("max tilt must be in (0, 90] degrees, got " + std::to_string(max_tilt_deg));
  if (!(estimate_prior_angle_deg > 0.0f && estimate_prior_angle_deg <= 90.0f))
    fail("the up prior angle must be in (0, 90] degrees, got " +
         std::to_string(estimate_prior_angle_deg));
  if (!(voxel_leaf >= 0.0f) || !std::isfinite(voxel_leaf))
    fail("voxel leaf must be >= 0, got " + std::to_string(voxel_leaf));
  if (!(table_band > 0.0f) || !std::isfinite(table_band))
    fail("table band must be positive, got " + std::to_string(table_band));
  if (!(table_connectivity > 0.0f) || !std::isfinite(table_connectivity))
    fail("table connectivity must be positive, got " + std::to_string(table_connectivity));
  if (!(table_min_part >= 0.0f && table_min_part <= 1.0f))
    fail("table min part must be in [0, 1], got " + std::to_string(table_min_part));
  if (!(min_table_parallel >= 0.0f && min_table_parallel <= 1.0f))
    fail("min table parallel must be in [0, 1], got " + std::to_string(min_table_parallel));
  if (!(table_normal_angle_deg > 0.0f && table_normal_angle_deg <= 90.0f))
    fail("table normal angle must be in (0, 90] degrees, got " +
         std::to_string(table_normal_angle_deg));
  const float min_height = min_object_height.value_or(-table_band);
  if (!std::isfinite(min_height) || !std::isfinite(max_object_height) ||
      min_height > max_object_height)
    fail("object height range [" + std::to_string(min_height) + ", " +
         std::to_string(max_object_height) + "] is empty");
  if (!std::isfinite(hull_margin)) fail("hull margin must be finite");
  plane.validate();
  clusters.validate();
  support.validate();
  table_noise.validate();
  creases.validate();
  shapes.validate();
  split.validate();
  merge.validate();
}

}  // namespace primlabel::tabletop
