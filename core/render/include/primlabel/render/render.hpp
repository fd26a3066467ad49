#pragma once
// Pictures of point clouds for people: a PNG of the points coloured per point (by label, by
// segment, ...), seen from above, obliquely or from the sensor, with an optional legend.

#include <cstdint>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel {

enum class RenderView {
  kTop,      // looking down the up axis
  kOblique,  // from above and to the side, the usual "table scene" picture
  kSensor,   // from the cloud's viewpoint, as the sensor saw it
};

struct LegendEntry {
  std::string name;
  std::uint32_t rgb;  // 0xRRGGBB
};

// A 3D polyline drawn over the points (no depth test: outlines of fitted primitives must show
// through the surface they were fitted to), e.g. from primitive_outlines().
struct Overlay {
  std::vector<Vec3f> points;
  std::uint32_t rgb = 0x000000;  // 0xRRGGBB
  bool closed = false;           // also join the last point to the first
  std::string label;             // drawn beside the first point, e.g. an object's id
};

struct RenderOptions {
  int width = 1024;
  int height = 768;
  RenderView view = RenderView::kOblique;
  Vec3f up = Vec3f(0, 0, 1);  // world up, for kTop and kOblique
  int point_radius_px = 1;    // splat size; 0 = single pixels
  std::uint32_t background = 0xFFFFFF;
  std::string title;                // drawn top-left when not empty
  std::vector<LegendEntry> legend;  // drawn bottom-left when not empty
  // Drawn over the points in the same projection; the picture is framed by the points only, so
  // an overlay beyond them is clipped at the image's edge.
  std::vector<Overlay> overlays;
  // The picture's height shrinks to what the points need at `width` (never below what the title
  // and legend need, never above `height`): no empty band above or below a wide scene.
  bool crop_to_points = false;
};

// The view a labeled cloud is best seen from: the sensor's for an organised cloud (a camera's
// frame: its own y points down, so a fixed "up" would show it upside down), else oblique.
RenderView natural_view(const PointCloud& cloud);

// Renders the finite points of `cloud` with colours `point_rgb` (0xRRGGBB, one per point) to a
// PNG at `path`, nearer points drawn over farther ones. Throws std::runtime_error naming the path
// when the file cannot be written, std::invalid_argument when the colours do not match the cloud.
void render_png(const PointCloud& cloud, const std::vector<std::uint32_t>& point_rgb,
                const RenderOptions& options, const std::string& path);

}  // namespace primlabel
