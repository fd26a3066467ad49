#include "primlabel/render/box_outlines.hpp"

namespace primlabel {

std::vector<Overlay> box_outline(const Vec3f& low, const Vec3f& high, std::uint32_t rgb,
                                 const std::string& label) {
  if (!is_finite(low) || !is_finite(high)) return {};
  const auto corner = [&](int x, int y, int z) {
    return Vec3f(x ? high.x() : low.x(), y ? high.y() : low.y(), z ? high.z() : low.z());
  };
  std::vector<Overlay> out;
  const auto add = [&](std::vector<Vec3f> points, bool closed) {
    Overlay edge;
    edge.points = std::move(points);
    edge.rgb = rgb;
    edge.closed = closed;
    out.push_back(std::move(edge));
  };
  // The top rectangle first, so its first point carries the label above the box.
  for (int z = 1; z >= 0; --z)
    add({corner(0, 0, z), corner(1, 0, z), corner(1, 1, z), corner(0, 1, z)}, true);
  out.front().label = label;
  for (int x = 0; x <= 1; ++x)
    for (int y = 0; y <= 1; ++y) add({corner(x, y, 0), corner(x, y, 1)}, false);
  return out;
}

std::vector<Overlay> table_top_outlines(const std::vector<Vec3f>& hull,
                                        const std::vector<LabeledBox>& boxes) {
  std::vector<Overlay> out;
  if (hull.size() >= 2) {
    Overlay outline;
    outline.points = hull;
    outline.rgb = 0x808080;
    outline.closed = true;
    out.push_back(std::move(outline));
  }
  for (const LabeledBox& box : boxes)
    for (Overlay& edge : box_outline(box.low, box.high, 0x000000, box.label))
      out.push_back(std::move(edge));
  return out;
}

}  // namespace primlabel
