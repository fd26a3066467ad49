#pragma once
// The crowded table with the hard cases of real ones (SceneKind::kCrowded). Internal to the
// synth library: make_scene is the way in.

#include <cstdint>

#include "primlabel/synth/scene.hpp"

namespace primlabel::synth::detail {

Scene crowded_scene(std::uint64_t seed);

}  // namespace primlabel::synth::detail
