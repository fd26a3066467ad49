#pragma once
// Training-scene augmentation: variants of a synthetic scene scanned with other range noise,
// density (random subsampling), sensor range and incidence, drawn reproducibly from the scene's
// seed, so models learn descriptors as other scans of the same shapes give them.
//
// Spec (primlabel-train --augment): comma-separated key=lo:hi ranges (or key=value) and copies=N,
//   noise=0.5:4,density=0.25:1,range=0.9:1.4,elevation=-10:10,copies=1
// noise multiplies the sensor noise (drawn log-uniformly: each octave as often), density is the
// share of points kept, range scales the sensor's distance, elevation (degrees) turns it about the
// table's front edge (SensorPlacement); the three are drawn uniformly. copies: augmented variants
// per training scene, besides the scene as the sensor scans it nominally.

#include <cstdint>
#include <string>
#include <string_view>

#include "primlabel/synth/generate.hpp"

namespace primlabel::synth {

struct AugmentRange {
  double lo = 1.0, hi = 1.0;
};

struct Augmentation {
  AugmentRange noise, density, range;
  AugmentRange elevation_deg{0.0, 0.0};
  int copies = 0;  // 0: no augmentation
};

// Throws std::invalid_argument naming the bad key or value.
Augmentation parse_augmentation(std::string_view spec);
std::string to_string(const Augmentation& augmentation);

// Variant `copy` (0-based) of the scene `base` describes: the same scene (base.seed), scanned with
// parameters drawn from mix_seed(base.seed, copy) and its own scan seed.
GenerateOptions augmented(const GenerateOptions& base, const Augmentation& augmentation, int copy);

}  // namespace primlabel::synth
