// Per-point answers near creases (pipeline/crease_points.hpp).

#include "primlabel/pipeline/crease_points.hpp"

#include <algorithm>
#include <stdexcept>

#include "primlabel/geometry/parallel.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::pipeline {

namespace {

constexpr std::size_t kBlock = 512;  // points per parallel block

std::ptrdiff_t blocks_of(std::size_t n) { return std::ptrdiff_t((n + kBlock - 1) / kBlock); }

// Per slot: 1 when it was inferred and an inferred neighbour within reach has another label.
std::vector<std::uint8_t> crease_slots(const SlotAnswers& slots, float voxel_size,
                                       const RunContext& context) {
  const std::vector<Vec3f>& xyz = *slots.xyz;
  const std::size_t n = xyz.size();
  std::vector<std::uint8_t> crease(n, 0);
  const Neighborhood hood = Neighborhood::Hybrid(kCreaseReach * voxel_size, 27);
  detail::for_each_block(
      blocks_of(n), context, [] { return NeighborList(); },
      [&](NeighborList& list, std::ptrdiff_t block) {
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        for (std::size_t s = first; s < last; ++s) {
          if (!slots.inferred[s]) continue;
          slots.search->find(xyz[s], hood, slots.inferred, list, /*sorted=*/false);
          crease[s] = std::any_of(list.indices.begin(), list.indices.end(), [&](std::uint32_t q) {
            return slots.labels[q] != slots.labels[s];
          });
        }
      });
  throw_if_stopped(context.stop, "the crease points");
  return crease;
}

}  // namespace

CreaseAnswers decide_crease_points(const std::vector<Vec3f>& points,
                                   std::span<const std::uint32_t> slot_of, const SlotAnswers& slots,
                                   float voxel_size, const RunContext& context) {
  const Eigen::MatrixXf& marginals = *slots.marginals;
  const std::size_t num_slots = slots.xyz->size();
  if (slot_of.size() != points.size() || slots.inferred.size() != num_slots ||
      slots.labels.size() != num_slots || std::size_t(marginals.rows()) != num_slots ||
      std::size_t(marginals.cols()) != slots.class_ids.size())
    throw std::invalid_argument("decide_crease_points: sizes do not match");
  const std::vector<std::uint8_t> crease = crease_slots(slots, voxel_size, context);

  CreaseAnswers answers;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (slot_of[i] != tabletop::kNoVoxel && crease[slot_of[i]])
      answers.points.push_back(std::uint32_t(i));
  const std::size_t n = answers.points.size();
  const Eigen::Index classes = marginals.cols();
  answers.labels.resize(n);
  answers.probabilities.resize(Eigen::Index(n), classes);
  // A point on a centroid would divide by 0: its own voxel then decides alone.
  const float closest = 1e-3f * voxel_size;
  const Neighborhood hood = Neighborhood::Knn(kCreaseNeighbors);
  detail::for_each_block(
      blocks_of(n), context, [] { return NeighborList(); },
      [&](NeighborList& list, std::ptrdiff_t block) {
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        Eigen::RowVectorXf row(classes);
        for (std::size_t j = first; j < last; ++j) {
          slots.search->find(points[answers.points[j]], hood, slots.inferred, list);
          row.setZero();
          float total = 0.0f;
          for (std::size_t m = 0; m < list.size(); ++m) {
            const float w = 1.0f / std::max(list.sq_dists[m], closest * closest);
            row += w * marginals.row(Eigen::Index(list.indices[m]));
            total += w;
          }
          row /= total;
          Eigen::Index best = 0;
          for (Eigen::Index k = 1; k < classes; ++k)
            if (row[k] > row[best]) best = k;  // strictly: ties keep the lowest column
          answers.probabilities.row(Eigen::Index(j)) = row;
          answers.labels[j] = slots.class_ids[std::size_t(best)];
        }
      });
  throw_if_stopped(context.stop, "the crease points");
  return answers;
}

}  // namespace primlabel::pipeline
