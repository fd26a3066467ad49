#pragma once
// Per-point colours and matching legends for render_png: by primitive class, by segment id, by
// the cloud's own rgb, or by a scalar through a colour map.

#include <cstdint>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/render/render.hpp"

namespace primlabel {

struct Coloring {
  std::vector<std::uint32_t> rgb;  // 0xRRGGBB per point
  std::vector<LegendEntry> legend;
};

// Labels through `map` to taxonomy classes and their colours; the legend lists the classes
// present with their share of the valid points. Labels missing from the map are dark grey and
// listed as "label N".
Coloring color_by_class(const PointCloud& cloud, const ClassMap& map);

// Any integer labels as segments: a distinct colour per id (0 grey); legend of up to
// `max_legend` ids by size.
Coloring color_by_segment(const PointCloud& cloud, int max_legend = 12);

// The cloud's rgb/rgba field; no legend. Requires cloud.has_rgba().
Coloring color_by_rgb(const PointCloud& cloud);

// `values` (one per point, NaN allowed) through a perceptual colour map (viridis) between their
// 1st and 99th percentiles; the legend shows the range under `name`.
Coloring color_by_value(const std::vector<float>& values, const std::string& name);

// Viridis at t in [0, 1].
std::uint32_t viridis(float t);

}  // namespace primlabel
