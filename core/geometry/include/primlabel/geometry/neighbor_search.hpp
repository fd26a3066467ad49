#pragma once
// Fixed-radius, k-nearest and hybrid neighbour queries over a cloud's finite points (nanoflann
// k-d tree). Results are sorted by ascending squared distance, ties by ascending index, so the
// same query always returns the same list.

#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <stop_token>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel {

// What a "neighbourhood" is. Radius search when radius > 0 and max_neighbors == 0; k-nearest when
// radius == 0 and k > 0; hybrid (the nearest max_neighbors within radius) when both are set.
struct Neighborhood {
  float radius = 0.0f;
  int k = 0;              // k-nearest (radius == 0)
  int max_neighbors = 0;  // cap for radius search; 0 = unlimited

  static Neighborhood Radius(float r) { return {r, 0, 0}; }
  static Neighborhood Knn(int k) { return {0.0f, k, 0}; }
  static Neighborhood Hybrid(float r, int max_nn) { return {r, 0, max_nn}; }

  // A radius must be finite (an infinite one would make every query read the whole cloud).
  bool valid() const {
    return (radius > 0.0f && std::isfinite(radius) && k == 0 && max_neighbors >= 0) ||
           (radius == 0.0f && k > 0);
  }
  std::string describe() const;
};

struct NeighborList {
  std::vector<std::uint32_t> indices;  // indices into the cloud the search was built on
  std::vector<float> sq_dists;
  std::size_t size() const { return indices.size(); }
  void clear() {
    indices.clear();
    sq_dists.clear();
  }
};

class NeighborSearch {
 public:
  // Indexes the finite points of `points` in place (nothing is copied); the vector must outlive
  // the search object and not change while it lives. The k-d tree is nanoflann's, built through
  // its public API; `stop` is checked before and after it, and during it for clouds of 2^19
  // points or more (every few hundred microseconds; the tree is the same as an unchecked build;
  // smaller builds take tens of milliseconds), and the constructor then
  // throws primlabel::Cancelled. It is also checked while a radius grid is built on first use of
  // a radius: a build cut short is not kept and the k-d tree answers instead (the same
  // neighbours; unsorted lists may come in another order), since the caller is about to give up.
  explicit NeighborSearch(const std::vector<Vec3f>& points, std::stop_token stop = {});
  ~NeighborSearch();
  NeighborSearch(const NeighborSearch&) = delete;
  NeighborSearch& operator=(const NeighborSearch&) = delete;

  // Neighbours of an arbitrary query position (the query point itself is included when it is in
  // the cloud, at distance 0). k-nearest results are always sorted; radius results are sorted
  // unless `sorted` is false, in which case their order is still deterministic (tree order) and
  // the O(n log n) sort is saved. A non-finite query has no neighbours.
  // A hybrid query costs O(max_neighbors log max_neighbors) whatever the cloud: the radius is
  // read directly only while it holds few points, else the nearest are searched, and the search
  // stops as soon as max_neighbors points at distance 0 are found (coincident points).
  // Thread-safe: the tree is read-only after construction.
  void find(const Vec3f& query, const Neighborhood& hood, NeighborList& out,
            bool sorted = true) const;

  // The same query among the points with allowed[i] != 0 only (`allowed` has one entry per
  // point of the cloud): the neighbours a search built on those points alone would return, but
  // on this one index. Ties at the last place of a k-nearest or capped list are broken by the
  // tree's visiting order, as always, which a smaller tree may visit differently.
  void find(const Vec3f& query, const Neighborhood& hood, std::span<const std::uint8_t> allowed,
            NeighborList& out, bool sorted = true) const;

  std::size_t indexed_points() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace primlabel
