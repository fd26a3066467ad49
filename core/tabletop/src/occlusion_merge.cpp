#include "primlabel/tabletop/occlusion_merge.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "primlabel/tabletop/convex_hull.hpp"
#include "surface_colour.hpp"

namespace primlabel::tabletop {

void OcclusionMergeOptions::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  const auto non_negative = [](float v) { return v >= 0.0f && std::isfinite(v); };
  if (!non_negative(depth_margin)) fail("occlusion merge depth margin must be >= 0");
  if (max_scan_pixels < 1) fail("occlusion merge max scan pixels must be at least 1");
  if (min_scanlines < 1) fail("occlusion merge min scanlines must be at least 1");
  if (!non_negative(top_tolerance)) fail("occlusion merge top tolerance must be >= 0");
  if (!non_negative(max_gap)) fail("occlusion merge max gap must be >= 0");
  if (!non_negative(footprint_margin)) fail("occlusion merge footprint margin must be >= 0");
  if (!non_negative(max_table_fraction)) fail("occlusion merge max table fraction must be >= 0");
  if (!non_negative(max_chromaticity_difference))
    fail("occlusion merge max chromaticity difference must be >= 0");
}

namespace {

struct Link {
  int across_occluder = 0;  // scanlines with pixels of a nearer surface between the two ends
  int adjacent = 0;         // scanlines where one end itself hides the other's continuation
  float gap = std::numeric_limits<float>::infinity();  // smallest 3D distance of linked ends
  int scanlines() const { return across_occluder + adjacent; }
};

// Finds, along image rows and columns, pairs of clusters separated only by occluding pixels.
class LinkScanner {
 public:
  LinkScanner(const PointCloud& cloud, const std::vector<std::vector<std::uint32_t>>& clusters,
              const OcclusionMergeOptions& options)
      : cloud_(cloud), options_(options), label_(cloud.size(), -1), range_(cloud.size()) {
    for (std::size_t k = 0; k < clusters.size(); ++k)
      for (std::uint32_t i : clusters[k]) label_[i] = static_cast<std::int32_t>(k);
    for (std::size_t i = 0; i < cloud.size(); ++i)
      range_[i] = is_finite(cloud.xyz[i]) ? (cloud.xyz[i] - cloud.viewpoint.origin).norm()
                                          : std::numeric_limits<float>::quiet_NaN();
  }

  std::map<std::pair<std::int32_t, std::int32_t>, Link> scan() {
    const std::size_t w = cloud_.width, h = cloud_.height;
    for (std::size_t row = 0; row < h; ++row) scan_line(row * w, 1, w);
    for (std::size_t col = 0; col < w; ++col) scan_line(col, w, h);
    return std::move(links_);
  }

 private:
  std::size_t pixel(std::size_t start, std::size_t step, std::size_t t) const {
    return start + t * step;
  }

  void scan_line(std::size_t start, std::size_t step, std::size_t length) {
    std::vector<std::int32_t> found;
    for (std::size_t t = 1; t < length; ++t) {
      const std::size_t p = pixel(start, step, t);
      const std::int32_t x = label_[p];
      if (x < 0 || label_[pixel(start, step, t - 1)] == x) continue;  // only where a run starts
      // Walk back over invalid pixels and pixels nearer than p; every other cluster met there is
      // a candidate.
      found.clear();
      const std::size_t reach = std::min<std::size_t>(t, std::size_t(options_.max_scan_pixels) + 1);
      for (std::size_t back = 1; back <= reach; ++back) {
        const std::size_t s = t - back;
        const std::size_t q = pixel(start, step, s);
        const std::int32_t y = label_[q];
        if (y == x) break;
        if (y >= 0 && std::find(found.begin(), found.end(), y) == found.end()) {
          found.push_back(y);
          const Gap gap = classify_gap(start, step, s, t);
          if (gap != Gap::kFreeSpace) add_link(y, x, q, p, gap == Gap::kOccluder);
        }
        if (!std::isnan(range_[q]) && !(range_[q] < range_[p] - options_.depth_margin)) break;
      }
    }
  }

  enum class Gap { kFreeSpace, kAdjacent, kOccluder };

  // kOccluder when the pixels strictly between s and t include valid ones and every valid one is
  // nearer than the straight line between the ranges at s and t by depth_margin; kAdjacent when
  // there is no valid pixel between them; kFreeSpace otherwise.
  Gap classify_gap(std::size_t start, std::size_t step, std::size_t s, std::size_t t) const {
    const float rs = range_[pixel(start, step, s)], rt = range_[pixel(start, step, t)];
    bool occluder = false;
    for (std::size_t k = s + 1; k < t; ++k) {
      const float r = range_[pixel(start, step, k)];
      if (std::isnan(r)) continue;
      const float line = rs + (rt - rs) * float(k - s) / float(t - s);
      if (!(r < line - options_.depth_margin)) return Gap::kFreeSpace;
      occluder = true;
    }
    return occluder ? Gap::kOccluder : Gap::kAdjacent;
  }

  void add_link(std::int32_t a, std::int32_t b, std::size_t pa, std::size_t pb, bool occluder) {
    Link& link = links_[{std::min(a, b), std::max(a, b)}];
    ++(occluder ? link.across_occluder : link.adjacent);
    link.gap = std::min(link.gap, (cloud_.xyz[pa] - cloud_.xyz[pb]).norm());
  }

  const PointCloud& cloud_;
  const OcclusionMergeOptions& options_;
  std::vector<std::int32_t> label_;
  std::vector<float> range_;
  std::map<std::pair<std::int32_t, std::int32_t>, Link> links_;
};

// Mean chromaticity (r, g) / (r + g + b) of the cluster's pixels that are not too dark to tell:
// the surface's material, largely independent of its shading. NaN without colour.
Eigen::Vector2f chromaticity(const std::vector<std::uint32_t>& cluster, const PointCloud& cloud) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  std::size_t counted = 0;
  if (cloud.has_rgba())
    for (std::uint32_t i : cluster)
      if (const auto chroma = colour::chromaticity(cloud.rgba[i])) {
        sum += *chroma;
        ++counted;
      }
  if (counted == 0) return Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
  return (sum / double(counted)).cast<float>();
}

// The height below which 99% of the cluster's points lie: the top, robust to flying pixels.
float top_height(const std::vector<std::uint32_t>& cluster, const std::vector<float>& height) {
  std::vector<float> h;
  h.reserve(cluster.size());
  for (std::uint32_t i : cluster) h.push_back(height[i]);
  const std::size_t k = h.size() - 1 - h.size() / 100;
  std::nth_element(h.begin(), h.begin() + k, h.end());
  return h[k];
}

}  // namespace

std::vector<std::vector<std::uint32_t>> merge_occluded(
    const PointCloud& cloud, const std::vector<float>& height, const PlaneGrid& table,
    std::vector<std::vector<std::uint32_t>> clusters, const OcclusionMergeOptions& options,
    const KeptApart& kept_apart) {
  options.validate();
  const auto by_size = [](const auto& a, const auto& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  };
  if (!options.enabled || !cloud.organized() ||
      std::size_t(cloud.width) * cloud.height != cloud.size() || clusters.size() < 2) {
    std::sort(clusters.begin(), clusters.end(), by_size);
    return clusters;
  }

  std::vector<std::pair<std::pair<std::int32_t, std::int32_t>, Link>> links;
  for (const auto& entry : LinkScanner(cloud, clusters, options).scan())
    if (entry.second.scanlines() >= options.min_scanlines) links.push_back(entry);
  std::stable_sort(links.begin(), links.end(), [](const auto& a, const auto& b) {
    return a.second.scanlines() > b.second.scanlines();
  });

  // Table cells this close to a part count as under it.
  const int under_cells = static_cast<int>(std::ceil(options.footprint_margin / table.cell()));
  // Groups of joined clusters: root, top height, footprint (cells and hull) and point count.
  const std::size_t n = clusters.size();
  std::vector<std::uint32_t> root(n);
  std::vector<float> top(n);
  std::vector<std::vector<std::uint64_t>> cells(n);
  std::vector<std::vector<Vec2f>> hull(n);
  std::vector<std::size_t> count(n);
  std::vector<Eigen::Vector2f> colour(n);  // per cluster, not per group: the linked surfaces'
  for (std::size_t k = 0; k < n; ++k) {
    colour[k] = chromaticity(clusters[k], cloud);
    root[k] = static_cast<std::uint32_t>(k);
    top[k] = top_height(clusters[k], height);
    cells[k] = table.footprint(cloud.xyz, clusters[k], under_cells);
    std::vector<Vec2f> footprint;
    footprint.reserve(clusters[k].size());
    for (std::uint32_t i : clusters[k]) footprint.push_back(table.project(cloud.xyz[i]));
    hull[k] = convex_hull(std::move(footprint));
    count[k] = clusters[k].size();
  }
  const auto find = [&](std::uint32_t k) {
    while (root[k] != k) k = root[k] = root[root[k]];
    return k;
  };
  // Per fitted solid (a can's, a ball's): the cluster holding it, none when no cluster does.
  std::vector<std::int64_t> solid_cluster(kept_apart.solids.size(), -1);
  if (!kept_apart.solids.empty()) {
    std::vector<std::int64_t> cluster_of(cloud.size(), -1);
    for (std::size_t k = 0; k < n; ++k)
      for (std::uint32_t i : clusters[k]) cluster_of[i] = std::int64_t(k);
    for (std::size_t s = 0; s < kept_apart.solids.size(); ++s)
      solid_cluster[s] = cluster_of[kept_apart.solids[s].anchor];
  }
  // Whether cluster k lies outside solid s (cached: asked again as groups grow).
  std::map<std::pair<std::size_t, std::size_t>, bool> outside;
  const auto outside_solid = [&](std::size_t s, std::size_t k) {
    const auto [at, added] = outside.try_emplace({s, k}, false);
    if (added) at->second = KeptApart::outside(kept_apart.solids[s], cloud.xyz, clusters[k]);
    return at->second;
  };
  // Every cluster lies in one piece of whatever a refinement cut apart, so its first point tells.
  // A cluster outside a solid another holds is another object.
  const auto held_apart = [&](std::uint32_t a, std::uint32_t b) {
    if (!kept_apart.piece.empty())
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j)
          if (find(std::uint32_t(i)) == a && find(std::uint32_t(j)) == b &&
              kept_apart.apart(clusters[i].front(), clusters[j].front()))
            return true;
    for (std::size_t s = 0; s < solid_cluster.size(); ++s) {
      if (solid_cluster[s] < 0) continue;
      const std::uint32_t own = find(std::uint32_t(solid_cluster[s]));
      if (own != a && own != b) continue;
      const std::uint32_t other = own == a ? b : a;
      for (std::size_t k = 0; k < n; ++k)
        if (find(std::uint32_t(k)) == other && outside_solid(s, k)) return true;
    }
    return false;
  };
  for (const auto& [pair, link] : links) {
    const std::uint32_t a = find(pair.first), b = find(pair.second);
    if (a == b || std::abs(top[a] - top[b]) > options.top_tolerance || link.gap > options.max_gap)
      continue;
    if (held_apart(a, b)) continue;
    // Without a separate occluder, neighbouring objects look the same: ask for one material.
    const float colour_difference = (colour[pair.first] - colour[pair.second]).norm();
    if (link.across_occluder < options.min_scanlines &&
        colour_difference > options.max_chromaticity_difference)
      continue;
    std::vector<Vec2f> joint = hull[a];
    joint.insert(joint.end(), hull[b].begin(), hull[b].end());
    joint = convex_hull(std::move(joint));
    // Table seen where neither part is above it: free space between them. (Table under a part,
    // e.g. beside a bowl's foot under its overhanging rim, says nothing.)
    std::vector<std::uint64_t> joint_cells;
    std::merge(cells[a].begin(), cells[a].end(), cells[b].begin(), cells[b].end(),
               std::back_inserter(joint_cells));
    const std::size_t table_inside =
        table.count_inside(joint, options.footprint_margin, joint_cells);
    if (double(table_inside) > options.max_table_fraction * double(count[a] + count[b])) continue;
    const std::uint32_t kept = std::min(a, b), gone = std::max(a, b);
    root[gone] = kept;
    top[kept] = std::max(top[a], top[b]);
    hull[kept] = std::move(joint);
    cells[kept] = std::move(joint_cells);
    count[kept] += count[gone];
  }

  std::vector<std::vector<std::uint32_t>> merged;
  std::vector<std::int64_t> slot(n, -1);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t r = find(static_cast<std::uint32_t>(k));
    if (slot[r] < 0) {
      slot[r] = static_cast<std::int64_t>(merged.size());
      merged.emplace_back();
    }
    auto& members = merged[slot[r]];
    members.insert(members.end(), clusters[k].begin(), clusters[k].end());
  }
  for (auto& members : merged) std::sort(members.begin(), members.end());
  std::sort(merged.begin(), merged.end(), by_size);
  return merged;
}

}  // namespace primlabel::tabletop
