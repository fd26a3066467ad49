#include "primlabel/tabletop/stacked_split.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "primlabel/tabletop/convex_hull.hpp"

namespace primlabel::tabletop {

void StackSplitOptions::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  const auto positive = [](float v) { return v > 0.0f && std::isfinite(v); };
  if (!positive(bin)) fail("stack split bin must be positive, got " + std::to_string(bin));
  if (!(min_support_height >= 0.0f) || !std::isfinite(min_support_height))
    fail("stack split min support height must be >= 0");
  if (!(peak_factor >= 1.0f) || !std::isfinite(peak_factor))
    fail("stack split peak factor must be >= 1, got " + std::to_string(peak_factor));
  if (!(min_rise >= 0.0f) || !std::isfinite(min_rise)) fail("stack split min rise must be >= 0");
  if (!(min_free_share > 0.0f && min_free_share <= 1.0f))
    fail("stack split min free share must be in (0, 1]");
  if (!(min_on_surface >= 0.0f && min_on_surface <= 1.0f))
    fail("stack split min on-surface fraction must be in [0, 1]");
  if (!(footprint_margin >= 0.0f) || !std::isfinite(footprint_margin))
    fail("stack split footprint margin must be >= 0");
}

namespace {

class Splitter {
 public:
  Splitter(const std::vector<Vec3f>& points, const std::vector<float>& height,
           const Eigen::Vector4f& plane, const StackSplitOptions& options)
      : points_(points), height_(height), options_(options) {
    plane_basis(plane.head<3>(), u_, v_);
  }

  // Splits `cluster` at its lowest qualifying support surface into (lower, upper); false when
  // there is none.
  bool split(const std::vector<std::uint32_t>& cluster, std::vector<std::uint32_t>& lower,
             std::vector<std::uint32_t>& upper) const {
    if (cluster.size() < 2 * options_.min_points) return false;
    float lowest = height_[cluster[0]], highest = lowest;
    for (std::uint32_t i : cluster) {
      lowest = std::min(lowest, height_[i]);
      highest = std::max(highest, height_[i]);
    }
    const auto bin_of = [&](float h) {
      return static_cast<std::size_t>(std::floor((h - lowest) / options_.bin));
    };
    std::vector<std::size_t> counts(bin_of(highest) + 1, 0);
    for (std::uint32_t i : cluster) ++counts[bin_of(height_[i])];
    std::vector<std::size_t> sorted = counts;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double peak =
        options_.peak_factor * double(std::max<std::size_t>(sorted[sorted.size() / 2], 1));

    for (std::size_t b = 0; b < counts.size();) {
      if (double(counts[b]) < peak ||
          lowest + float(b) * options_.bin < options_.min_support_height) {
        ++b;
        continue;
      }
      std::size_t e = b;  // the surface's band: the run of peak bins [b, e)
      while (e < counts.size() && double(counts[e]) >= peak) ++e;
      // One more bin either side takes in the surface's noise and slight tilt.
      const float band_low = lowest + (float(b) - 1.0f) * options_.bin;
      const float band_top = lowest + (float(e) + 1.0f) * options_.bin;
      if (try_split(cluster, band_low, band_top, highest, lower, upper)) return true;
      b = e;
    }
    return false;
  }

 private:
  Vec2f project(std::uint32_t i) const { return Vec2f(points_[i].dot(u_), points_[i].dot(v_)); }

  bool try_split(const std::vector<std::uint32_t>& cluster, float band_low, float band_top,
                 float highest, std::vector<std::uint32_t>& lower,
                 std::vector<std::uint32_t>& upper) const {
    if (highest < band_top + options_.min_rise) return false;
    std::vector<Vec2f> surface, above;
    for (std::uint32_t i : cluster) {
      const float h = height_[i];
      if (h >= band_top)
        above.push_back(project(i));
      else if (h >= band_low)
        surface.push_back(project(i));
    }
    if (above.size() < options_.min_points) return false;
    const std::vector<Vec2f> surface_hull = convex_hull(surface);
    const std::vector<Vec2f> above_hull = convex_hull(above);
    if (surface_hull.size() < 3 || above_hull.size() < 3) return false;
    // The support's visible part lies outside the upper object's footprint (the rest is hidden
    // under it); a container's floor lies inside its walls' footprint.
    std::size_t free = 0;
    for (const Vec2f& q : surface) free += !hull_contains(above_hull, q, options_.footprint_margin);
    if (double(free) < options_.min_free_share * double(surface.size())) return false;
    std::size_t on_surface = 0;
    for (const Vec2f& q : above)
      on_surface += hull_contains(surface_hull, q, options_.footprint_margin);
    if (double(on_surface) < options_.min_on_surface * double(above.size())) return false;

    // The surface under the upper object is hidden, so what the band holds inside the upper
    // object's footprint is the upper object's base.
    lower.clear();
    upper.clear();
    for (std::uint32_t i : cluster) {
      const float h = height_[i];
      const bool is_upper =
          h >= band_top || (h >= band_low && hull_contains(above_hull, project(i), 0.0f));
      (is_upper ? upper : lower).push_back(i);
    }
    return upper.size() >= options_.min_points && lower.size() >= options_.min_points;
  }

  const std::vector<Vec3f>& points_;
  const std::vector<float>& height_;
  const StackSplitOptions& options_;
  Vec3f u_, v_;
};

}  // namespace

std::vector<std::vector<std::uint32_t>> split_stacked(
    const std::vector<Vec3f>& points, const std::vector<float>& height,
    const Eigen::Vector4f& plane, std::vector<std::vector<std::uint32_t>> clusters,
    const StackSplitOptions& options) {
  options.validate();
  if (options.enabled) {
    const Splitter splitter(points, height, plane, options);
    std::vector<std::vector<std::uint32_t>> done, pending = std::move(clusters);
    while (!pending.empty()) {
      std::vector<std::uint32_t> cluster = std::move(pending.back());
      pending.pop_back();
      std::vector<std::uint32_t> lower, upper;
      if (splitter.split(cluster, lower, upper)) {
        pending.push_back(std::move(lower));  // each may hold more stacked objects
        pending.push_back(std::move(upper));
      } else {
        done.push_back(std::move(cluster));
      }
    }
    clusters = std::move(done);
  }
  std::sort(clusters.begin(), clusters.end(), [](const auto& a, const auto& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  return clusters;
}

}  // namespace primlabel::tabletop
