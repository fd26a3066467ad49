#include "primlabel/tabletop/tabletop_objects.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace primlabel::tabletop {

namespace {
constexpr std::uint32_t kNoSegment = 0xFFFFFFFFu;
}  // namespace

TabletopObjects object_ids(const TabletopResult& result, std::size_t num_points) {
  TabletopObjects out;
  out.point_object.assign(num_points, kNoObject);
  if (!result.ok()) {
    out.message = result.message.empty() ? to_string(result.status) : result.message;
    return out;
  }
  out.table = TabletopTable{result.plane, result.hull, 0, {}};
  const std::vector<std::int32_t> ids = segment_ids(result, num_points);
  for (std::size_t i = 0; i < num_points; ++i)
    if (ids[i] >= 0) out.point_object[i] = static_cast<std::uint32_t>(ids[i]);
  out.objects.resize(result.clusters.size());
  for (std::size_t k = 0; k < out.objects.size(); ++k)
    out.objects[k].id = static_cast<std::uint32_t>(k + 1);
  return out;
}

void describe_objects(const std::vector<Vec3f>& xyz, TabletopObjects& objects) {
  if (objects.point_object.size() != xyz.size())
    throw std::invalid_argument("describe_objects: " + std::to_string(objects.point_object.size()) +
                                " object ids for " + std::to_string(xyz.size()) + " points");
  if (!objects.table) return;
  const std::size_t count = objects.objects.size();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> sums(count, Eigen::Vector3d::Zero());
  for (TabletopObject& object : objects.objects) {
    object.points = 0;
    object.bounds_min = Eigen::Vector3d::Constant(kInf);
    object.bounds_max = Eigen::Vector3d::Constant(-kInf);
    object.height = -kInf;
  }
  objects.table->points = 0;
  const Eigen::Vector4d plane = objects.table->plane.cast<double>();
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    const std::uint32_t id = objects.point_object[i];
    if (id == kNoObject) continue;
    if (id == kTableObject) {
      ++objects.table->points;
      continue;
    }
    if (id > count) throw std::invalid_argument("describe_objects: object id out of range");
    TabletopObject& object = objects.objects[id - 1];
    const Eigen::Vector3d p = xyz[i].cast<double>();
    ++object.points;
    sums[id - 1] += p;
    object.bounds_min = object.bounds_min.cwiseMin(p);
    object.bounds_max = object.bounds_max.cwiseMax(p);
    object.height = std::max(object.height, plane.head<3>().dot(p) + plane[3]);
  }
  for (std::size_t k = 0; k < count; ++k) {
    TabletopObject& object = objects.objects[k];
    if (object.points == 0) {  // keeps the id; nothing to measure
      object.bounds_min = object.bounds_max = Eigen::Vector3d::Zero();
      object.height = 0;
      continue;
    }
    object.centroid = sums[k] / double(object.points);
  }
  // Largest first by the points counted here: the stage ordered its clusters by voxels, and a
  // voxel of a near object holds more points than one of a far object.
  std::vector<std::uint32_t> order(count);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return objects.objects[a].points > objects.objects[b].points;
  });
  std::vector<std::uint32_t> new_id(count + 1, 0);
  std::vector<TabletopObject> sorted;
  sorted.reserve(count);
  for (std::uint32_t rank = 0; rank < count; ++rank) {
    new_id[order[rank] + 1] = rank + 1;
    sorted.push_back(std::move(objects.objects[order[rank]]));
    sorted.back().id = rank + 1;
  }
  objects.objects = std::move(sorted);
  for (std::uint32_t& id : objects.point_object)
    if (id != kNoObject && id != kTableObject) id = new_id[id];
}

void assign_primitives(std::span<const std::uint32_t> point_segment,
                       std::span<const std::size_t> segment_points, TabletopObjects& objects) {
  if (point_segment.size() != objects.point_object.size())
    throw std::invalid_argument("assign_primitives: " + std::to_string(point_segment.size()) +
                                " segment ids for " + std::to_string(objects.point_object.size()) +
                                " points");
  if (!objects.table) return;
  const std::size_t segments = segment_points.size();
  // Boyer-Moore majority vote per segment, then a count of the candidate: two linear passes.
  std::vector<std::uint32_t> candidate(segments, kNoObject);
  std::vector<std::size_t> votes(segments, 0);
  for (std::size_t i = 0; i < point_segment.size(); ++i) {
    const std::uint32_t s = point_segment[i];
    if (s == kNoSegment) continue;
    if (s >= segments) throw std::invalid_argument("assign_primitives: segment id out of range");
    const std::uint32_t id = objects.point_object[i];
    if (votes[s] == 0) {
      candidate[s] = id;
      votes[s] = 1;
    } else if (candidate[s] == id) {
      ++votes[s];
    } else {
      --votes[s];
    }
  }
  std::vector<std::size_t> support(segments, 0);
  for (std::size_t i = 0; i < point_segment.size(); ++i) {
    const std::uint32_t s = point_segment[i];
    if (s != kNoSegment && objects.point_object[i] == candidate[s]) ++support[s];
  }
  objects.table->primitive_ids.clear();
  for (TabletopObject& object : objects.objects) object.primitive_ids.clear();
  for (std::size_t s = 0; s < segments; ++s) {
    const std::uint32_t id = candidate[s];
    if (id == kNoObject || 2 * support[s] <= segment_points[s]) continue;
    const auto segment = static_cast<std::uint32_t>(s);
    if (id == kTableObject)
      objects.table->primitive_ids.push_back(segment);
    else if (id <= objects.objects.size())
      objects.objects[id - 1].primitive_ids.push_back(segment);
  }
}

}  // namespace primlabel::tabletop
