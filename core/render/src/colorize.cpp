#include "primlabel/render/colorize.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

namespace primlabel {
namespace {

constexpr std::uint32_t kUnmappedColor = 0x505050;
constexpr std::uint32_t kBackgroundSwatch = 0xFFFFFF;  // points without a position: not drawn

std::string percent(std::size_t n, std::size_t total) {
  char text[32];
  std::snprintf(text, sizeof text, " %.1f%%", total ? 100.0 * double(n) / double(total) : 0.0);
  return text;
}

// Well-separated colours, given to the segment ids present in ascending order (so ids that
// differ by a multiple of the palette size still differ when there are fewer segments than
// colours); id 0 is grey.
constexpr std::array<std::uint32_t, 20> kSegmentPalette = {
    0xE6194B, 0x3CB44B, 0x4363D8, 0xF58231, 0x911EB4, 0x42D4F4, 0xF032E6,
    0xBFEF45, 0xFABED4, 0x469990, 0xDCBEFF, 0x9A6324, 0xFFE119, 0x800000,
    0xAAFFC3, 0x808000, 0xFFD8B1, 0x000075, 0xA9A9A9, 0x2F4F4F};
constexpr std::uint32_t kSegmentZeroColor = 0xB0B0B0;

}  // namespace

Coloring color_by_class(const PointCloud& cloud, const ClassMap& map) {
  if (!cloud.has_labels()) throw std::invalid_argument("the cloud has no 'label' field");
  Coloring out;
  out.rgb.resize(cloud.size(), kUnmappedColor);
  // Shares of every point, so they agree with the labels' own counts (the CLI's line): the
  // points without a position (NaN pixels of a frame) get an entry of their own.
  std::map<std::uint32_t, std::size_t> counts;  // by label, points with a position
  std::size_t no_position = 0;
  const std::size_t total = cloud.size();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto cls = map.class_of(cloud.labels[i]);
    if (cls) out.rgb[i] = color(*cls);
    if (!is_finite(cloud.xyz[i])) {
      ++no_position;
      continue;
    }
    ++counts[cloud.labels[i]];
  }
  // Legend in taxonomy order (several labels may share a class).
  std::map<std::uint32_t, std::size_t> by_class;
  std::vector<std::pair<std::uint32_t, std::size_t>> unmapped;
  for (const auto& [label, n] : counts) {
    if (const auto cls = map.class_of(label))
      by_class[class_id(*cls)] += n;
    else
      unmapped.emplace_back(label, n);
  }
  for (const auto& [id, n] : by_class) {
    const PrimitiveClass cls = *class_from_id(id);
    out.legend.push_back({std::string(name(cls)) + percent(n, total), color(cls)});
  }
  for (const auto& [label, n] : unmapped)
    out.legend.push_back({"label " + std::to_string(label) + percent(n, total), kUnmappedColor});
  if (no_position > 0)
    out.legend.push_back({"no point (NaN)" + percent(no_position, total), kBackgroundSwatch});
  return out;
}

Coloring color_by_segment(const PointCloud& cloud, int max_legend) {
  if (!cloud.has_labels()) throw std::invalid_argument("the cloud has no 'label' field");
  std::map<std::uint32_t, std::size_t> counts;  // every id present, valid points per id
  std::size_t valid = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    std::size_t& n = counts[cloud.labels[i]];
    if (!is_finite(cloud.xyz[i])) continue;
    ++valid;
    ++n;
  }
  std::map<std::uint32_t, std::uint32_t> palette;
  std::size_t rank = 0;
  for (const auto& [id, n] : counts)
    palette[id] = id == 0 ? kSegmentZeroColor : kSegmentPalette[rank++ % kSegmentPalette.size()];
  Coloring out;
  out.rgb.resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) out.rgb[i] = palette[cloud.labels[i]];

  std::vector<std::pair<std::size_t, std::uint32_t>> by_size;
  for (const auto& [label, n] : counts)
    if (n > 0) by_size.emplace_back(n, label);
  std::sort(by_size.begin(), by_size.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  const std::size_t shown = std::min<std::size_t>(by_size.size(), std::max(max_legend, 1));
  std::vector<std::uint32_t> ids;
  for (std::size_t i = 0; i < shown; ++i) ids.push_back(by_size[i].second);
  std::sort(ids.begin(), ids.end());
  for (std::uint32_t id : ids)
    out.legend.push_back(
        {"segment " + std::to_string(id) + percent(counts[id], valid), palette[id]});
  if (by_size.size() > shown)
    out.legend.push_back({"(" + std::to_string(by_size.size() - shown) + " more)", 0xFFFFFF});
  return out;
}

Coloring color_by_rgb(const PointCloud& cloud) {
  if (!cloud.has_rgba()) throw std::invalid_argument("the cloud has no 'rgb' or 'rgba' field");
  Coloring out;
  out.rgb.resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) out.rgb[i] = cloud.rgba[i] & 0xFFFFFF;
  return out;
}

std::uint32_t viridis(float t) {
  static constexpr std::array<std::array<float, 3>, 9> kStops = {{{68, 1, 84},
                                                                  {71, 44, 122},
                                                                  {59, 81, 139},
                                                                  {44, 113, 142},
                                                                  {33, 144, 141},
                                                                  {39, 173, 129},
                                                                  {92, 200, 99},
                                                                  {170, 220, 50},
                                                                  {253, 231, 37}}};
  if (!std::isfinite(t)) return 0x808080;
  const float x = std::clamp(t, 0.0f, 1.0f) * (kStops.size() - 1);
  const std::size_t i = std::min<std::size_t>(std::size_t(x), kStops.size() - 2);
  const float f = x - float(i);
  std::uint32_t rgb = 0;
  for (int c = 0; c < 3; ++c)
    rgb =
        rgb << 8 | std::uint32_t(std::lround(kStops[i][c] + f * (kStops[i + 1][c] - kStops[i][c])));
  return rgb;
}

Coloring color_by_value(const std::vector<float>& values, const std::string& field_name) {
  std::vector<float> finite;
  for (float v : values)
    if (std::isfinite(v)) finite.push_back(v);
  Coloring out;
  out.rgb.resize(values.size(), 0x808080);
  if (finite.empty()) {
    out.legend.push_back({field_name + ": no finite values", 0x808080});
    return out;
  }
  auto quantile = [&](double q) {
    const std::size_t k = std::min(finite.size() - 1, std::size_t(q * double(finite.size() - 1)));
    std::nth_element(finite.begin(), finite.begin() + k, finite.end());
    return finite[k];
  };
  const float lo = quantile(0.01), hi = quantile(0.99);
  const float span = hi > lo ? hi - lo : 1.0f;
  for (std::size_t i = 0; i < values.size(); ++i)
    if (std::isfinite(values[i])) out.rgb[i] = viridis((values[i] - lo) / span);
  char text[64];
  for (float t : {1.0f, 0.5f, 0.0f}) {
    std::snprintf(text, sizeof text, "%s %.4g", field_name.c_str(), lo + t * (hi - lo));
    out.legend.push_back({text, viridis(t)});
  }
  return out;
}

}  // namespace primlabel
