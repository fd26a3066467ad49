// Segments, then one fit per segment, in parallel: a segment is a block of work with a seed of
// its own (from its lowest point index), so neither the thread count nor the other segments
// change its fit.

#include "primlabel/primitives/fit_primitives.hpp"

#include <chrono>
#include <stdexcept>
#include <string>

#include "fit_support.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel::primitives {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The segment's label, size, centroid and bounds.
Primitive describe_segment(const std::vector<Vec3f>& xyz, const std::vector<std::uint32_t>& indices,
                           std::uint32_t label) {
  Primitive p;
  p.class_id = label;
  p.points = indices.size();
  p.first_point = indices.front();
  Vec3d sum = Vec3d::Zero();
  p.bounds_min = Vec3d::Constant(INFINITY);
  p.bounds_max = Vec3d::Constant(-INFINITY);
  for (std::uint32_t i : indices) {
    const Vec3d q = xyz[i].cast<double>();
    sum += q;
    p.bounds_min = p.bounds_min.cwiseMin(q);
    p.bounds_max = p.bounds_max.cwiseMax(q);
  }
  p.centroid = sum / double(indices.size());
  return p;
}

}  // namespace

void PrimitiveOptions::validate() const {
  segments.validate();
  fit.validate();
}

PrimitiveSet fit_primitives(const std::vector<Vec3f>& xyz, std::span<const Vec3f> normals,
                            std::span<const std::uint32_t> labels, const PrimitiveOptions& options,
                            const RunContext& context, const SharedNeighbors& shared) {
  options.validate();
  if (!normals.empty() && normals.size() != xyz.size())
    throw std::invalid_argument("primitives: " + std::to_string(normals.size()) + " normals for " +
                                std::to_string(xyz.size()) + " points");
  PrimitiveSet out;
  auto start = std::chrono::steady_clock::now();
  Segmentation segmentation = segment_by_label(xyz, labels, options.segments, context, shared);
  out.segment_seconds = seconds_since(start);
  out.segment_radius = segmentation.radius;
  start = std::chrono::steady_clock::now();
  out.primitives.resize(segmentation.segments.size());
  primlabel::detail::for_each_block(
      std::ptrdiff_t(segmentation.segments.size()), context, [] { return 0; },
      [&](int&, std::ptrdiff_t s) {
        const std::vector<std::uint32_t>& indices = segmentation.segments[std::size_t(s)];
        Primitive& primitive = out.primitives[std::size_t(s)];
        primitive = describe_segment(xyz, indices, segmentation.labels[std::size_t(s)]);
        const SegmentPoints points{xyz, normals, indices};
        const std::optional<Fit> fit =
            fit_model(model_for_class(primitive.class_id), points, options.fit,
                      detail::mix_seed(options.seed, primitive.first_point));
        if (!fit) return;
        primitive.model = fit->model;
        primitive.inliers = fit->inliers;
        primitive.rms = fit->rms;
        primitive.confidence = fit->confidence;
      });
  context.throw_if_stopped("primitive fitting");
  out.point_segment = std::move(segmentation.point_segment);
  out.fit_seconds = seconds_since(start);
  return out;
}

}  // namespace primlabel::primitives
