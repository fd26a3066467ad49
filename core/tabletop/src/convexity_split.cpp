#include "primlabel/tabletop/convexity_split.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "disjoint_sets.hpp"
#include "surface_colour.hpp"

namespace primlabel::tabletop {

void ConvexitySplitOptions::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (!(patch_size > 0.0f) || !std::isfinite(patch_size))
    fail("convexity split patch size must be positive, got " + std::to_string(patch_size));
  if (!(concavity_tolerance_deg >= 0.0f && concavity_tolerance_deg < 90.0f))
    fail("convexity split concavity tolerance must be in [0, 90) degrees, got " +
         std::to_string(concavity_tolerance_deg));
}

namespace {

constexpr double kDegree = M_PI / 180.0;

struct Patch {
  std::int32_t x, y, z;
  std::vector<std::uint32_t> members;  // input indices, ascending
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // zero when undefined
  bool has_normal = false;
  Eigen::Vector2d chroma_sum = Eigen::Vector2d::Zero();  // (r, g) / (r + g + b) of lit points
  std::size_t chroma_count = 0;
};

// Sums of points and their outer products, relative to an origin, for a least-squares plane.
struct Moments {
  std::size_t count = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d products = Eigen::Matrix3d::Zero();
  void add(const Moments& m) {
    count += m.count;
    sum += m.sum;
    products += m.products;
  }
};

std::uint64_t key_of(std::int32_t x, std::int32_t y, std::int32_t z) {
  const auto bits = [](std::int32_t v) { return std::uint64_t(std::uint32_t(v) & 0x1FFFFFu); };
  return bits(z) << 42 | bits(y) << 21 | bits(x);
}

// LCCP's sanity criterion (extended convexity): the largest angle between d and n_i x n_j at which
// a connection with normals beta apart is still taken for a step, not a fold.
double singular_angle_limit(double beta_deg) {
  constexpr double kMax = 60.0, kOffset = 25.0, kSlope = 0.25;
  return kMax / (1.0 + std::exp(-kSlope * (beta_deg - kOffset)));
}

class CreaseSplitter {
 public:
  CreaseSplitter(const PointCloud& cloud, const ConvexitySplitOptions& options)
      : points_(cloud.xyz),
        rgba_(cloud.rgba),
        viewpoint_(cloud.viewpoint.origin.cast<double>()),
        options_(options) {}

  std::vector<std::vector<std::uint32_t>> split(const std::vector<std::uint32_t>& cluster) {
    if (cluster.size() < 2 * options_.min_segment_points) return {cluster};
    build_patches(cluster);
    const std::size_t n = patches_.size();
    std::vector<std::pair<std::uint32_t, std::uint32_t>> neighbours;  // (i, j), i < j
    for (std::uint32_t i = 0; i < n; ++i)
      for_each_neighbour(i, edge_reach_, [&](std::uint32_t j) {
        if (i < j) neighbours.emplace_back(i, j);
      });

    // Segments: patches joined through convex connections; patches without a normal join all
    // their neighbours only in the size pass below.
    DisjointSets segments(n);
    for (const auto& [i, j] : neighbours)
      if (convex(patches_[i], patches_[j])) segments.join(i, j);

    // Segment sizes and the connections between segments.
    std::vector<std::size_t> size(n, 0);
    for (std::uint32_t i = 0; i < n; ++i) size[segments.find(i)] += patches_[i].members.size();
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> contact;
    for (const auto& [i, j] : neighbours) {
      const std::uint32_t a = segments.find(i), b = segments.find(j);
      if (a != b) ++contact[{std::min(a, b), std::max(a, b)}];
    }
    join_small_segments(segments, size, contact);
    join_isolated_segments(segments, size);
    keep_only_creases(segments, neighbours);

    std::map<std::uint32_t, std::vector<std::uint32_t>> pieces;
    for (std::uint32_t i = 0; i < n; ++i) {
      auto& piece = pieces[segments.find(i)];
      piece.insert(piece.end(), patches_[i].members.begin(), patches_[i].members.end());
    }
    std::vector<std::vector<std::uint32_t>> out;
    for (auto& [root, members] : pieces) {
      std::sort(members.begin(), members.end());
      out.push_back(std::move(members));
    }
    return out;
  }

 private:
  void build_patches(const std::vector<std::uint32_t>& cluster) {
    patches_.clear();
    index_.clear();
    const double leaf = options_.patch_size;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
    keyed.reserve(cluster.size());
    std::vector<std::array<std::int32_t, 3>> cell(cluster.size());
    Eigen::Vector3d lowest = points_[cluster.front()].cast<double>();
    for (std::uint32_t i : cluster) lowest = lowest.cwiseMin(points_[i].cast<double>());
    origin_ = lowest;
    for (std::size_t k = 0; k < cluster.size(); ++k) {
      const Eigen::Vector3d p = (points_[cluster[k]].cast<double>() - lowest) / leaf;
      cell[k] = {std::int32_t(p.x()), std::int32_t(p.y()), std::int32_t(p.z())};
      keyed.emplace_back(key_of(cell[k][0], cell[k][1], cell[k][2]), std::uint32_t(k));
    }
    std::sort(keyed.begin(), keyed.end());
    std::vector<Moments> moments;
    for (std::size_t k = 0; k < keyed.size(); ++k) {
      const std::uint32_t local = keyed[k].second;
      if (k == 0 || keyed[k].first != keyed[k - 1].first) {
        const auto& c = cell[local];
        index_.emplace(keyed[k].first, std::uint32_t(patches_.size()));
        patches_.push_back(Patch{c[0], c[1], c[2], {}});
        moments.emplace_back();
      }
      const std::uint32_t i = cluster[local];
      patches_.back().members.push_back(i);
      if (!rgba_.empty())
        if (const auto chroma = colour::chromaticity(rgba_[i])) {
          patches_.back().chroma_sum += *chroma;
          ++patches_.back().chroma_count;
        }
      const Eigen::Vector3d p = points_[i].cast<double>() - origin_;
      Moments& m = moments.back();
      ++m.count;
      m.sum += p;
      m.products += p * p.transpose();
    }
    for (std::uint32_t i = 0; i < patches_.size(); ++i) {
      Patch& patch = patches_[i];
      std::sort(patch.members.begin(), patch.members.end());
      patch.centroid = moments[i].sum / double(moments[i].count);
      Moments around = moments[i];
      for_each_neighbour(i, normal_reach_, [&](std::uint32_t j) { around.add(moments[j]); });
      if (around.count < 6) continue;
      const Eigen::Vector3d mean = around.sum / double(around.count);
      const Eigen::Matrix3d covariance =
          around.products / double(around.count) - mean * mean.transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
      // A line of points (one scan row) has no surface normal.
      if (solver.eigenvalues()[1] < 1e-3 * solver.eigenvalues()[2]) continue;
      Eigen::Vector3d normal = solver.eigenvectors().col(0);
      if (normal.dot(viewpoint_ - (patch.centroid + origin_)) < 0) normal = -normal;
      patch.normal = normal;
      patch.has_normal = true;
    }
  }

  template <typename F>
  void for_each_neighbour(std::uint32_t i, int reach, F&& f) const {
    const Patch& p = patches_[i];
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int steps = std::abs(dx) + std::abs(dy) + std::abs(dz);
          if (steps == 0 || steps > reach) continue;
          const auto it = index_.find(key_of(p.x + dx, p.y + dy, p.z + dz));
          if (it != index_.end()) f(it->second);
        }
  }

  // A concave fold between a and b: both have normals, they bend toward each other and their
  // normals are at least the tolerance apart. Returns the angle between the normals (deg), or a
  // negative value when the connection is not such a fold.
  double fold_angle(const Patch& a, const Patch& b) const {
    if (!a.has_normal || !b.has_normal) return -1.0;
    const double beta_deg = std::acos(std::clamp(a.normal.dot(b.normal), -1.0, 1.0)) / kDegree;
    const Eigen::Vector3d d = (a.centroid - b.centroid).normalized();
    if (beta_deg < options_.concavity_tolerance_deg || a.normal.dot(d) - b.normal.dot(d) > 0.0)
      return -1.0;
    return beta_deg;
  }

  bool convex(const Patch& a, const Patch& b) const {
    if (!a.has_normal || !b.has_normal) return false;
    const double cos_beta = std::clamp(a.normal.dot(b.normal), -1.0, 1.0);
    const double beta_deg = std::acos(cos_beta) / kDegree;
    Eigen::Vector3d d = a.centroid - b.centroid;
    const double length = d.norm();
    if (length < 1e-9) return true;
    d /= length;
    const bool bends_away = a.normal.dot(d) - b.normal.dot(d) > 0.0;
    if (!bends_away && beta_deg >= options_.concavity_tolerance_deg) return false;
    if (options_.sanity_check && beta_deg >= options_.concavity_tolerance_deg) {
      const Eigen::Vector3d s = a.normal.cross(b.normal);
      const double s_norm = s.norm();
      if (s_norm > 1e-9) {
        const double c = std::abs(std::clamp(s.dot(d) / s_norm, -1.0, 1.0));
        const double theta_deg = std::acos(c) / kDegree;  // in [0, 90]
        if (theta_deg < singular_angle_limit(beta_deg)) return false;
      }
    }
    return true;
  }

  // Joins every segment smaller than min_segment_points to the neighbour it touches most
  // (ties: the larger, then the lower root), smallest first; isolated small segments stay.
  void join_small_segments(
      DisjointSets& segments, std::vector<std::size_t>& size,
      std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t>& contact) {
    for (;;) {
      // The smallest segment that has a neighbour and is too small.
      std::uint32_t small = UINT32_MAX;
      for (const auto& [pair, count] : contact)
        for (std::uint32_t s : {pair.first, pair.second})
          if (size[s] < options_.min_segment_points &&
              (small == UINT32_MAX || size[s] < size[small] ||
               (size[s] == size[small] && s < small)))
            small = s;
      if (small == UINT32_MAX) return;
      std::uint32_t best = UINT32_MAX;
      std::size_t best_contact = 0;
      for (const auto& [pair, count] : contact) {
        if (pair.first != small && pair.second != small) continue;
        const std::uint32_t other = pair.first == small ? pair.second : pair.first;
        if (best == UINT32_MAX || count > best_contact ||
            (count == best_contact && size[other] > size[best])) {
          best = other;
          best_contact = count;
        }
      }
      // Merge `small` into `best` and rewrite the contacts.
      segments.join(small, best);
      const std::uint32_t root = segments.find(small);
      const std::uint32_t gone = root == small ? best : small;
      size[root] = size[small] + size[best];
      std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> updated;
      for (const auto& [pair, count] : contact) {
        std::uint32_t a = pair.first == gone ? root : pair.first;
        std::uint32_t b = pair.second == gone ? root : pair.second;
        if (a == b) continue;
        updated[{std::min(a, b), std::max(a, b)}] += count;
      }
      contact = std::move(updated);
    }
  }

  // A small segment touching no other patch (within the clustering tolerance, but not in a
  // neighbouring voxel) joins the segment of the nearest patch centroid.
  void join_isolated_segments(DisjointSets& segments, std::vector<std::size_t>& size) {
    const std::uint32_t n = static_cast<std::uint32_t>(patches_.size());
    for (;;) {
      std::uint32_t small = UINT32_MAX;
      std::size_t segment_count = 0;
      for (std::uint32_t i = 0; i < n; ++i) {
        if (segments.find(i) != i) continue;
        ++segment_count;
        if (size[i] < options_.min_segment_points && (small == UINT32_MAX || size[i] < size[small]))
          small = i;
      }
      if (small == UINT32_MAX || segment_count < 2) return;
      std::uint32_t nearest = UINT32_MAX;
      double best = std::numeric_limits<double>::infinity();
      for (std::uint32_t i = 0; i < n; ++i) {
        if (segments.find(i) != small) continue;
        for (std::uint32_t j = 0; j < n; ++j) {
          if (segments.find(j) == small) continue;
          const double d = (patches_[i].centroid - patches_[j].centroid).squaredNorm();
          if (d < best) {
            best = d;
            nearest = j;
          }
        }
      }
      const std::uint32_t other = segments.find(nearest);
      const std::size_t joined = size[small] + size[other];
      segments.join(small, other);
      size[segments.find(small)] = joined;
    }
  }

  // A cut between two segments stands only where they meet at a crease: most of their patch
  // connections are concave folds, and the fold is sharp (the faces of two objects) or the
  // segments differ in colour. A container's inside against its floor or its outer wall folds
  // gently or not at all, in one material. Rejected cuts are joined, the longest first.
  void keep_only_creases(DisjointSets& segments,
                         const std::vector<std::pair<std::uint32_t, std::uint32_t>>& neighbours) {
    for (;;) {
      struct Boundary {
        std::size_t connections = 0, folds = 0;
        double fold_sum = 0.0;
      };
      std::map<std::pair<std::uint32_t, std::uint32_t>, Boundary> boundaries;
      for (const auto& [i, j] : neighbours) {
        const std::uint32_t a = segments.find(i), b = segments.find(j);
        if (a == b) continue;
        Boundary& boundary = boundaries[{std::min(a, b), std::max(a, b)}];
        ++boundary.connections;
        const double fold = fold_angle(patches_[i], patches_[j]);
        if (fold >= 0.0) {
          ++boundary.folds;
          boundary.fold_sum += fold;
        }
      }
      if (boundaries.empty()) return;
      std::map<std::uint32_t, std::pair<Eigen::Vector2d, std::size_t>> colour;
      for (std::uint32_t i = 0; i < patches_.size(); ++i) {
        auto& c = colour.try_emplace(segments.find(i), Eigen::Vector2d::Zero(), 0).first->second;
        c.first += patches_[i].chroma_sum;
        c.second += patches_[i].chroma_count;
      }
      const auto colour_difference = [&](std::uint32_t a, std::uint32_t b) {
        const auto& ca = colour[a];
        const auto& cb = colour[b];
        if (ca.second == 0 || cb.second == 0) return 0.0;
        return (ca.first / double(ca.second) - cb.first / double(cb.second)).norm();
      };
      std::pair<std::uint32_t, std::uint32_t> rejected{UINT32_MAX, UINT32_MAX};
      std::size_t rejected_length = 0;
      for (const auto& [pair, boundary] : boundaries) {
        const double fold_share = double(boundary.folds) / double(boundary.connections);
        const double mean_fold = boundary.folds ? boundary.fold_sum / double(boundary.folds) : 0.0;
        const double colour_gap = colour_difference(pair.first, pair.second);
        const bool crease = fold_share >= options_.min_fold_share &&
                            (mean_fold >= options_.sharp_fold_deg ||
                             colour_gap > options_.min_chromaticity_difference);
        if (!crease && boundary.connections > rejected_length) {
          rejected = pair;
          rejected_length = boundary.connections;
        }
      }
      if (rejected_length == 0) return;
      segments.join(rejected.first, rejected.second);
    }
  }

  // Connections and normals both reach only the 6 face neighbours: across a crease, diagonal
  // links and normals averaged over 27 patches blend the two faces into a chain of gentle,
  // seemingly smooth steps that joins the objects again.
  static constexpr int edge_reach_ = 1, normal_reach_ = 1;
  const std::vector<Vec3f>& points_;
  const std::vector<std::uint32_t>& rgba_;
  Eigen::Vector3d viewpoint_;
  const ConvexitySplitOptions& options_;
  Eigen::Vector3d origin_;
  std::vector<Patch> patches_;
  std::map<std::uint64_t, std::uint32_t> index_;
};

}  // namespace

std::vector<std::vector<std::uint32_t>> split_at_concave_creases(
    const PointCloud& cloud, std::vector<std::vector<std::uint32_t>> clusters,
    const ConvexitySplitOptions& options) {
  options.validate();
  std::vector<std::vector<std::uint32_t>> out;
  // Normals face the sensor only in a single view (an organised scan); a merged or synthetic
  // cloud may hold surfaces the VIEWPOINT never saw, whose flipped normals would fake creases.
  if (!options.enabled || !cloud.organized()) {
    out = std::move(clusters);
  } else {
    CreaseSplitter splitter(cloud, options);
    for (const auto& cluster : clusters) {
      if (cluster.empty()) continue;
      for (auto& piece : splitter.split(cluster)) out.push_back(std::move(piece));
    }
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  return out;
}

}  // namespace primlabel::tabletop
