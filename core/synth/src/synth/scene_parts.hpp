#pragma once
// The building blocks the scene kinds share: the table slab, the kitchen objects drawn at random,
// and the area in front of the sensor where they stand. Internal to the synth library.

#include <Eigen/Geometry>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <vector>

#include "primlabel/synth/random.hpp"
#include "primlabel/synth/scene.hpp"

namespace primlabel::synth::detail {

Eigen::Isometry3d pose_on_table(double x, double y, double yaw);

std::uint32_t pick_color(Rng& rng, std::initializer_list<std::uint32_t> palette);

struct Candidate {
  std::shared_ptr<const Shape> shape;
  std::uint32_t rgb;
};

// A kitchen object in a realistic size: a box (tea, cereal, crackers), can, mug or cup, bowl,
// ball or ring.
Candidate random_object(Rng& rng);

// The table slab alone (objects[0]); its size is drawn when `random_size`.
Scene table_only(Rng& rng, bool random_size);

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
  std::optional<Eigen::Isometry3d> place(Rng& rng, double r, double gap);
  // As place, but the footprint then slides along the line to the nearest placed one until it is
  // `gap` from it (objects in contact); nothing when that spot is off the area or overlaps
  // another.
  std::optional<Eigen::Isometry3d> place_against(Rng& rng, double r, double gap);
};

}  // namespace primlabel::synth::detail
