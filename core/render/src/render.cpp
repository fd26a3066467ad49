// A small software rasteriser for point clouds: project, splat with a z-buffer, outline depth
// discontinuities so shapes read in 3D, draw a title and a legend with the built-in font, and
// write a PNG (Raster).

#include "primlabel/render/render.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>

#include "primlabel/render/raster.hpp"

namespace primlabel {
namespace {

// A view: screen axes (right, up) and viewing direction; perspective from `eye` when set.
struct Camera {
  Vec3f right, up, forward;
  bool perspective = false;
  Vec3f eye = Vec3f::Zero();

  // Screen coordinates (x right, y up) and depth along the view; false behind a pinhole.
  bool project(const Vec3f& p, float& x, float& y, float& depth) const {
    const Vec3f q = perspective ? Vec3f(p - eye) : p;
    depth = q.dot(forward);
    x = q.dot(right);
    y = q.dot(up);
    if (!perspective) return true;
    if (depth <= 1e-6f) return false;
    x /= depth;
    y /= depth;
    return true;
  }
};

Vec3f any_perpendicular(const Vec3f& v) {
  const Vec3f trial = std::abs(v.x()) < 0.9f ? Vec3f::UnitX() : Vec3f::UnitY();
  return (trial - trial.dot(v) * v).normalized();
}

// A pinhole at `eye` with the optical axes of `orientation` (sensor frames have y down).
Camera pinhole(const Vec3f& eye, const Eigen::Quaternionf& orientation) {
  const Eigen::Matrix3f r = orientation.normalized().toRotationMatrix();
  Camera camera;
  camera.perspective = true;
  camera.eye = eye;
  camera.forward = r.col(2);
  camera.right = r.col(0);
  camera.up = -r.col(1);
  return camera;
}

// Finite points (a sample of at most ~20000) that `camera` sees in front of it.
std::size_t points_in_front(const PointCloud& cloud, const Camera& camera) {
  const std::size_t stride = std::max<std::size_t>(1, cloud.size() / 20000);
  std::size_t n = 0;
  for (std::size_t i = 0; i < cloud.size(); i += stride) {
    float x, y, depth;
    n += is_finite(cloud.xyz[i]) && camera.project(cloud.xyz[i], x, y, depth);
  }
  return n;
}

// The sensor's view. VIEWPOINT is the sensor's pose in the cloud's frame (PCL's meaning), but
// many camera frames keep their points in the optical frame and store a mounting rotation there
// (PCL's office1.pcd): through that pose every point is behind the pinhole and the picture would
// be blank. So the pose that sees more points wins, the VIEWPOINT's or the optical frame's own;
// nothing if neither sees any.
std::optional<Camera> sensor_camera(const PointCloud& cloud) {
  const Camera stated = pinhole(cloud.viewpoint.origin, cloud.viewpoint.orientation);
  const Camera optical = pinhole(Vec3f::Zero(), Eigen::Quaternionf::Identity());
  const std::size_t seen_stated = points_in_front(cloud, stated);
  const std::size_t seen_optical = points_in_front(cloud, optical);
  if (seen_stated == 0 && seen_optical == 0) return std::nullopt;
  return seen_optical > seen_stated ? optical : stated;
}

Camera make_camera(const PointCloud& cloud, const RenderOptions& options) {
  Camera camera;
  if (options.view == RenderView::kSensor) {
    if (const std::optional<Camera> sensor = sensor_camera(cloud)) return *sensor;
    // No pose sees a point: the oblique view rather than an empty picture.
  }
  const Vec3f up = options.up.norm() > 0 ? options.up.normalized() : Vec3f::UnitZ();
  // Look the way the sensor looked (horizontally), so "oblique" resembles the scan.
  Vec3f centroid = Vec3f::Zero();
  std::size_t n = 0;
  for (const Vec3f& p : cloud.xyz)
    if (is_finite(p)) {
      centroid += p;
      ++n;
    }
  if (n) centroid /= float(n);
  Vec3f heading = centroid - cloud.viewpoint.origin;
  heading -= heading.dot(up) * up;
  if (heading.norm() < 1e-3f * std::max(1.0f, centroid.norm())) {
    // No usable viewpoint (e.g. a camera-frame cloud): use the viewpoint's optical axis, else
    // any horizontal direction.
    heading = cloud.viewpoint.orientation.normalized() * Vec3f::UnitZ();
    heading -= heading.dot(up) * up;
    if (heading.norm() < 1e-3f) heading = any_perpendicular(up);
  }
  heading.normalize();
  if (options.view == RenderView::kTop) {
    camera.forward = -up;
    camera.up = heading;  // the sensor at the bottom of the picture
  } else {
    const float elevation = 40.0f * float(M_PI) / 180.0f;
    camera.forward = (std::cos(elevation) * heading - std::sin(elevation) * up).normalized();
    camera.up = (up - up.dot(camera.forward) * camera.forward).normalized();
  }
  camera.right = camera.forward.cross(camera.up);
  return camera;
}

std::uint32_t scale_color(std::uint32_t c, float f) {
  auto ch = [&](int shift) {
    return std::uint32_t(std::clamp(float((c >> shift) & 0xFF) * f, 0.0f, 255.0f)) << shift;
  };
  return ch(16) | ch(8) | ch(0);
}

// Each overlay segment between two points the camera can see (a pinhole view drops segments
// reaching behind it rather than wrapping them around).
template <class ToPixel>
void draw_overlays(Raster& image, const Camera& camera, const std::vector<Overlay>& overlays,
                   const ToPixel& to_pixel, int text_scale) {
  const int thickness = image.width() >= 600 ? 3 : 2;
  for (const Overlay& overlay : overlays) {
    float lx, ly, ld;
    if (!overlay.label.empty() && !overlay.points.empty() && is_finite(overlay.points.front()) &&
        camera.project(overlay.points.front(), lx, ly, ld)) {
      float px, py;
      to_pixel(lx, ly, px, py);
      image.text(int(std::lround(px)) + 2 * text_scale,
                 int(std::lround(py)) - Raster::text_height(text_scale) - 2 * text_scale,
                 overlay.label, overlay.rgb & 0xFFFFFF, text_scale);
    }
    const std::size_t n = overlay.points.size();
    const std::size_t segments = overlay.closed && n > 2 ? n : (n ? n - 1 : 0);
    for (std::size_t s = 0; s < segments; ++s) {
      const Vec3f& a = overlay.points[s];
      const Vec3f& b = overlay.points[(s + 1) % n];
      float ax, ay, ad, bx, by, bd;
      if (!is_finite(a) || !is_finite(b) || !camera.project(a, ax, ay, ad) ||
          !camera.project(b, bx, by, bd))
        continue;
      float x0, y0, x1, y1;
      to_pixel(ax, ay, x0, y0);
      to_pixel(bx, by, x1, y1);
      // Far off-screen ends (a huge fitted plane) would make Raster::line walk a long way.
      const float limit = 4.0f * float(std::max(image.width(), image.height()));
      if (std::abs(x0) > limit || std::abs(y0) > limit || std::abs(x1) > limit ||
          std::abs(y1) > limit)
        continue;
      image.line(x0, y0, x1, y1, overlay.rgb & 0xFFFFFF, thickness);
    }
  }
}

}  // namespace

RenderView natural_view(const PointCloud& cloud) {
  return cloud.organized() ? RenderView::kSensor : RenderView::kOblique;
}

void render_png(const PointCloud& cloud, const std::vector<std::uint32_t>& point_rgb,
                const RenderOptions& options, const std::string& path) {
  if (point_rgb.size() != cloud.size())
    throw std::invalid_argument("render: " + std::to_string(point_rgb.size()) + " colours for " +
                                std::to_string(cloud.size()) + " points");
  if (options.width < 64 || options.height < 64 || options.width > 16384 || options.height > 16384)
    throw std::invalid_argument("render: image size must be 64..16384 pixels a side");

  const int text_scale = options.width >= 600 ? 2 : 1;
  const int line_height = Raster::text_height(text_scale) + 4 * text_scale;
  const int margin = 6 * text_scale;

  // Plot area: below the title, right of the legend column.
  const int title_height = options.title.empty() ? 0 : line_height + 2 * margin;
  int legend_width = 0;
  for (const LegendEntry& entry : options.legend)
    legend_width = std::max(legend_width, Raster::text_width(entry.name, text_scale));
  if (!options.legend.empty()) legend_width += 3 * margin + line_height;
  const int plot_x = legend_width + margin, plot_y = title_height + margin;
  const int plot_w = options.width - plot_x - margin;
  int height = options.height;
  if (plot_w < 16 || height - plot_y - margin < 16)
    throw std::invalid_argument("render: image too small for the title and legend");

  // Project every finite point.
  const Camera camera = make_camera(cloud, options);
  struct Projected {
    float x, y, depth;
    std::uint32_t index;
  };
  std::vector<Projected> projected;
  projected.reserve(cloud.size());
  float min_x = INFINITY, max_x = -INFINITY, min_y = INFINITY, max_y = -INFINITY;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!is_finite(cloud.xyz[i])) continue;
    Projected p{0, 0, 0, std::uint32_t(i)};
    if (!camera.project(cloud.xyz[i], p.x, p.y, p.depth)) continue;
    min_x = std::min(min_x, p.x), max_x = std::max(max_x, p.x);
    min_y = std::min(min_y, p.y), max_y = std::max(max_y, p.y);
    projected.push_back(p);
  }

  if (options.crop_to_points && !projected.empty()) {
    const float span_x = std::max(max_x - min_x, 1e-6f), span_y = std::max(max_y - min_y, 1e-6f);
    const int legend_height =
        options.legend.empty() ? 0 : int(options.legend.size()) * line_height + 2 * margin;
    const int needed = plot_y + int(std::ceil(float(plot_w) * span_y / span_x / 0.98f)) + margin;
    height = std::clamp(std::max(needed, title_height + legend_height + margin), 64, height);
  }
  const int plot_h = height - plot_y - margin;
  Raster image(options.width, height, options.background);
  std::vector<std::uint32_t>& pixels = image.pixels();

  if (!projected.empty()) {
    const float span_x = std::max(max_x - min_x, 1e-6f), span_y = std::max(max_y - min_y, 1e-6f);
    const float scale = 0.98f * std::min(plot_w / span_x, plot_h / span_y);
    const float offset_x = plot_x + 0.5f * (plot_w - scale * span_x);
    const float offset_y = plot_y + 0.5f * (plot_h - scale * span_y);
    // Screen position of a projected point, in pixels.
    const auto to_pixel = [&](float x, float y, float& px, float& py) {
      px = offset_x + scale * (x - min_x);
      py = offset_y + scale * (max_y - y);
    };
    // Depth in pixel units, so outline strength does not depend on the cloud's size.
    const float depth_scale = camera.perspective ? 1.0f : scale;
    std::vector<float> zbuffer(pixels.size(), INFINITY);
    std::vector<std::uint32_t> color(pixels.size(), 0);
    const int r = std::max(options.point_radius_px, 0);
    for (const Projected& p : projected) {
      float px, py;
      to_pixel(p.x, p.y, px, py);
      const int cx = int(std::lround(px)), cy = int(std::lround(py));
      const float depth = camera.perspective ? std::log(p.depth) * scale : p.depth * depth_scale;
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          if (dx * dx + dy * dy > r * r + r) continue;  // round splats
          const int x = cx + dx, y = cy + dy;
          if (x < 0 || y < 0 || x >= image.width() || y >= image.height()) continue;
          const std::size_t at = std::size_t(y) * image.width() + x;
          if (depth < zbuffer[at]) {
            zbuffer[at] = depth;
            color[at] = point_rgb[p.index] & 0xFFFFFF;
          }
        }
    }
    // Outlines: a pixel behind its neighbourhood's mean depth is at a silhouette or a crease.
    const int ring = 2;
    for (int y = 0; y < image.height(); ++y)
      for (int x = 0; x < image.width(); ++x) {
        const std::size_t at = std::size_t(y) * image.width() + x;
        if (!std::isfinite(zbuffer[at])) continue;
        float sum = 0;
        int n = 0;
        bool border = false;
        for (int dy = -ring; dy <= ring; dy += ring)
          for (int dx = -ring; dx <= ring; dx += ring) {
            if (!dx && !dy) continue;
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= image.width() || ny >= image.height()) continue;
            const float z = zbuffer[std::size_t(ny) * image.width() + nx];
            if (!std::isfinite(z)) {
              border = true;
              continue;
            }
            sum += z;
            ++n;
          }
        float shade = border ? 0.75f : 1.0f;
        if (n) shade *= std::max(0.35f, std::exp(-0.25f * std::max(0.0f, zbuffer[at] - sum / n)));
        pixels[at] = scale_color(color[at], shade);
      }
    draw_overlays(image, camera, options.overlays, to_pixel, text_scale);
  }

  if (!options.title.empty()) image.text(margin, margin, options.title, 0x202020, text_scale);
  if (!options.legend.empty()) {
    const int rows = static_cast<int>(options.legend.size());
    int y = height - margin - rows * line_height;
    image.fill(margin / 2, y - margin / 2, legend_width, rows * line_height + margin, 0xF4F4F4);
    for (const LegendEntry& entry : options.legend) {
      const int swatch = line_height - 3 * text_scale;
      image.fill(margin, y, swatch, swatch, 0x404040);
      image.fill(margin + 1, y + 1, swatch - 2, swatch - 2, entry.rgb & 0xFFFFFF);
      image.text(margin + swatch + margin, y + (swatch - Raster::text_height(text_scale)) / 2,
                 entry.name, 0x202020, text_scale);
      y += line_height;
    }
  }
  image.write_png(path);
}

}  // namespace primlabel
