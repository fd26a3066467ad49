#pragma once
// Colour evidence for the table-top refinements (the crease cut, the shape split, the occlusion
// merge): a surface's material is its pixels' chromaticity (r, g) / (r + g + b), which its
// shading scales away. Pixels too dark to tell are not counted.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace primlabel::tabletop::colour {

// The chromaticity of a packed 0xAARRGGBB colour; nothing when too dark to tell.
std::optional<Eigen::Vector2d> chromaticity(std::uint32_t rgba);

struct Material {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  double variance = 0;    // mean squared distance from the mean
  std::size_t count = 0;  // 0: too few pixels to tell
};
Material material_of(const std::vector<Eigen::Vector2d>& colours, std::size_t least);

// What a two-colour explanation must show: the share of the colour variance it explains, the
// least distance between the two colours and, to tell two even materials from a print, how many
// times the groups' own spread that distance must be.
struct TwoColourRule {
  double explained = 0.8;
  double step = 0.05;
  double separation = 4.0;
  std::size_t least = 60;  // pixels in either group
};

// Two even materials clearly apart (as the rule says of two groups).
bool different(const Material& a, const Material& b, const TwoColourRule& rule);
// One even material: the same colour within half the rule's step, each spread less than that.
bool same(const Material& a, const Material& b, const TwoColourRule& rule);

// The height at which the colour changes from one below to another above, when that one step
// explains the rule's share of the variation, both parts rise min_rise and hold rule.least
// samples. `samples` are (height, chromaticity), in any order.
std::optional<double> height_step(std::vector<std::pair<double, Eigen::Vector2d>> samples,
                                  double min_rise, const TwoColourRule& rule);

// Two groups of colours (two means, started at the extremes of the main spread) that explain the
// rule's share of the variation, each of one even colour clearly apart from the other: per
// colour its group (0 or 1). Nothing otherwise.
std::optional<std::vector<std::uint8_t>> two_materials(const std::vector<Eigen::Vector2d>& colours,
                                                       const TwoColourRule& rule);

}  // namespace primlabel::tabletop::colour
