#pragma once
// The finite points of a caller's xyz, as the k-d tree and the radius grid index them: search
// index i is the i-th finite point in cloud order. Nothing is copied; when every point is finite
// (the usual case once a filter has run) there is no index list either and search index ==
// cloud index, so the tree reads the caller's array directly.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <stop_token>
#include <vector>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::detail {

class FinitePoints {
 public:
  // `points` must outlive this object. Throws Cancelled when `stop` is requested during the
  // scan (checked every 64k points, about a millisecond).
  FinitePoints(const FinitePoints&) = delete;  // map_ points into to_cloud_
  FinitePoints& operator=(const FinitePoints&) = delete;
  FinitePoints(const std::vector<Vec3f>& points, const std::stop_token& stop)
      : points_(points.data()), cloud_size_(points.size()), size_(points.size()) {
    if (points.size() > std::numeric_limits<std::uint32_t>::max())
      throw std::invalid_argument("neighbour search: more than 2^32-1 points");
    constexpr std::size_t kCheckEvery = std::size_t(1) << 16;
    std::size_t first_bad = points.size();
    for (std::size_t i = 0; i < points.size() && first_bad == points.size(); ++i) {
      if (i % kCheckEvery == 0) throw_if_stopped(stop, "building the neighbour index");
      if (!is_finite(points[i])) first_bad = i;
    }
    if (first_bad == points.size()) return;
    to_cloud_.reserve(points.size());
    for (std::size_t i = 0; i < first_bad; ++i) to_cloud_.push_back(static_cast<std::uint32_t>(i));
    for (std::size_t i = first_bad; i < points.size(); ++i) {
      if (i % kCheckEvery == 0) throw_if_stopped(stop, "building the neighbour index");
      if (is_finite(points[i])) to_cloud_.push_back(static_cast<std::uint32_t>(i));
    }
    size_ = to_cloud_.size();
    map_ = to_cloud_.data();
  }

  std::size_t size() const { return size_; }
  std::size_t cloud_size() const { return cloud_size_; }
  std::uint32_t cloud_index(std::size_t i) const {
    return map_ ? map_[i] : static_cast<std::uint32_t>(i);
  }
  const Vec3f& operator[](std::size_t i) const { return points_[cloud_index(i)]; }
  const Vec3f* cloud() const { return points_; }     // indexed by cloud index
  const std::uint32_t* map() const { return map_; }  // nullptr: cloud index == index

 private:
  const Vec3f* points_;
  std::size_t cloud_size_;
  std::size_t size_;
  std::vector<std::uint32_t> to_cloud_;  // empty when every point is finite
  const std::uint32_t* map_ = nullptr;   // to_cloud_.data(), or nullptr: the identity
};

}  // namespace primlabel::detail
