// Labeling a cloud with a trained model: optionally downsample to voxels, optionally restrict to
// the table-top, describe with the model's settings (or allowed overrides), build its graph,
// infer (CRF or node-only) or classify point by point (SVM), and carry the results back to every
// input point.

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "labeling_options.hpp"
#include "multi_scale_input.hpp"
#include "primlabel/crf/inference.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/pipeline/domain.hpp"
#include "primlabel/pipeline/duplicates.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/svm_model.hpp"
#include "primlabel/tabletop/tabletop.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"

namespace primlabel::pipeline {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The primitives of the labeled input cloud, reusing the neighbour index, shared lists and point
// spacing that described it (the same segments as a search of its own, ~4x faster).
void fit_primitives_of_input(const PointCloud& cloud, const DescribedCloud& described,
                             const LabelingOptions& options, const RunContext& context,
                             LabelingResult& result) {
  const auto start = std::chrono::steady_clock::now();
  const primitives::SharedNeighbors shared{described.search.get(), described.lists.get(),
                                           described.point_spacing};
  result.primitives = primitives::fit_primitives(cloud.xyz, cloud.normals, result.labels,
                                                 options.primitives, context, shared);
  result.primitive_seconds = seconds_since(start);
}

// Every point of `cloud` described and labeled (no duplicates expected, see label_all_points).
// When `cloud` is the input cloud itself (`input`) and primitives are wanted, they are fitted
// here, while its neighbour index and lists are alive.
LabelingResult label_distinct_points(const LabelModel& model, const FeatureSettings& features,
                                     PointCloud& cloud, const LabelingOptions& options,
                                     const RunContext& context, const PointCloud* input = nullptr) {
  LabelingResult result;
  result.class_ids = model.class_ids();
  DescribeOptions describe_options;
  describe_options.use_cloud_normals = options.use_cloud_normals;
  describe_options.share_neighbor_lists = options.share_neighbor_lists;
  DescribedCloud described = describe_cloud(cloud, features, describe_options, context);
  result.normal_seconds = described.normal_seconds;
  result.descriptor_seconds = described.feature_seconds;
  result.feature_seconds = described.normal_seconds + described.feature_seconds;
  result.index_seconds = described.index_seconds;
  result.lists_seconds = described.lists_seconds;
  result.described_points = cloud.size();
  result.point_spacing = described.point_spacing;
  result.surface_variation = described.surface_variation;
  context.throw_if_stopped("labeling");
  if (model.kind == ModelKind::kSvm) {  // point by point: no graph
    classify_with_svm(model, std::move(described), options, context, result);
    return result;
  }

  const auto start = std::chrono::steady_clock::now();
  crf::GraphSettings graph_options = model.graph;
  // A node-only model ignores edges, so its graph needs none (only the active mask).
  if (model.kind == ModelKind::kNodeOnly) graph_options.neighborhood = Neighborhood::Knn(1);
  const crf::Graph graph = build_scene_graph(cloud, described, graph_options, context);
  result.graph_seconds = seconds_since(start);
  context.throw_if_stopped("labeling");
  crf::InferenceOutputs outputs;
  outputs.unknown_label = class_id(PrimitiveClass::kUnknown);
  outputs.marginals = options.want_probabilities;
  crf::InferenceResult inferred =
      infer(model.weights, described.descriptors, graph, model.inference, outputs, context);
  result.inference_seconds = seconds_since(start);

  result.labels = std::move(inferred.labels);
  if (options.want_probabilities) result.probabilities = std::move(inferred.marginals);
  if (options.want_descriptors)
    result.descriptors =
        leading_values(std::move(described.descriptors), model.features.descriptor_dim());
  result.labeled_points = graph.num_active();
  if (options.want_primitives && input == &cloud)
    fit_primitives_of_input(cloud, described, options, context, result);
  return result;
}

// An empty result for `points` points: every label unknown, NaN rows where asked.
LabelingResult unknown_result(std::size_t points, const LabelingResult& like,
                              const LabelingOptions& options) {
  LabelingResult result;
  result.class_ids = like.class_ids;
  result.labeled_points = like.labeled_points;
  result.described_points = like.described_points;
  result.prefilter_seconds = like.prefilter_seconds;
  result.normal_seconds = like.normal_seconds;
  result.descriptor_seconds = like.descriptor_seconds;
  result.feature_seconds = like.feature_seconds;
  result.inference_seconds = like.inference_seconds;
  result.voxel_seconds = like.voxel_seconds;
  result.index_seconds = like.index_seconds;
  result.lists_seconds = like.lists_seconds;
  result.graph_seconds = like.graph_seconds;
  result.fanout_seconds = like.fanout_seconds;
  result.point_spacing = like.point_spacing;
  result.surface_variation = like.surface_variation;
  result.labels.assign(points, class_id(PrimitiveClass::kUnknown));
  if (options.want_probabilities)
    result.probabilities =
        Eigen::MatrixXf::Constant(Eigen::Index(points), Eigen::Index(like.class_ids.size()), kNaN);
  if (options.want_descriptors) {
    result.descriptors = Descriptors::filled(points, like.descriptors.dim, kNaN);
  }
  return result;
}

// Copies the results of part point `from` to point `to` of the whole.
void copy_point(const LabelingResult& part, std::size_t from, LabelingResult& whole,
                std::size_t to) {
  whole.labels[to] = part.labels[from];
  if (part.probabilities.size() > 0)
    whole.probabilities.row(Eigen::Index(to)) = part.probabilities.row(Eigen::Index(from));
  if (!part.descriptors.empty()) {
    const std::span<const float> row = part.descriptors.row(from);
    std::copy(row.begin(), row.end(), whole.descriptors.row(to).begin());
  }
}

// The results of `part` (a cloud of distinct points or voxels) carried to every point of the
// whole cloud through `slot_of` (kNoVoxel: the point was not described and stays unknown),
// normals and curvature included unless the cloud's own normals were used.
LabelingResult fan_out(const LabelingResult& partial, const PointCloud& part,
                       const std::vector<std::uint32_t>& slot_of, PointCloud& cloud,
                       const LabelingOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  LabelingResult result = unknown_result(cloud.size(), partial, options);
  result.labeled_points = 0;
  if (!options.use_cloud_normals) {
    cloud.normals.assign(cloud.size(), Vec3f::Constant(kNaN));
    cloud.curvature.assign(cloud.size(), kNaN);
  }
  const std::uint32_t unknown = class_id(PrimitiveClass::kUnknown);
  if (partial.objects) {  // the ids go with the labels; counts and shapes come at the end
    result.objects = partial.objects;
    result.objects->point_object.assign(cloud.size(), tabletop::kNoObject);
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const std::uint32_t j = slot_of[i];
    if (j == tabletop::kNoVoxel) continue;
    copy_point(partial, j, result, i);
    if (partial.objects) result.objects->point_object[i] = partial.objects->point_object[j];
    if (partial.labels[j] != unknown) ++result.labeled_points;
    if (!options.use_cloud_normals) {
      cloud.normals[i] = part.normals[j];
      cloud.curvature[i] = part.curvature[j];
    }
  }
  result.fanout_seconds += seconds_since(start);
  return result;
}

// The points `indices` of `cloud` as a cloud of their own (unorganised, same viewpoint), with
// their normals when the cloud's own normals are used.
PointCloud gather(const PointCloud& cloud, const std::vector<std::uint32_t>& indices,
                  bool with_normals) {
  PointCloud part;
  part.resize_unorganized(indices.size());
  part.viewpoint = cloud.viewpoint;
  for (std::size_t j = 0; j < indices.size(); ++j) part.xyz[j] = cloud.xyz[indices[j]];
  if (with_normals) {
    part.normals.resize(indices.size());
    for (std::size_t j = 0; j < indices.size(); ++j) part.normals[j] = cloud.normals[indices[j]];
  }
  return part;
}

// Exact duplicates are described once, at their lowest index, and every copy gets that copy's
// results (as voxels fan out to their members below).
LabelingResult label_all_points(const LabelModel& model, const FeatureSettings& features,
                                PointCloud& cloud, const LabelingOptions& options,
                                const RunContext& context, const PointCloud* input = nullptr) {
  const DuplicateMap duplicates = find_duplicates(cloud.xyz, context.stop);
  if (!duplicates.any())
    return label_distinct_points(model, features, cloud, options, context, input);
  PointCloud distinct = gather(cloud, duplicates.representatives, options.use_cloud_normals);
  const LabelingResult partial = label_distinct_points(model, features, distinct, options, context);
  return fan_out(partial, distinct, duplicates.slot_of, cloud, options);
}

// Table-top only: label the sub-cloud of table and object points, scatter back.
LabelingResult label_tabletop(const LabelModel& model, const FeatureSettings& features,
                              PointCloud& cloud, const LabelingOptions& options,
                              const RunContext& context) {
  const auto start = std::chrono::steady_clock::now();
  tabletop::TabletopOptions tabletop_options;
  const tabletop::TabletopResult segmented =
      tabletop::segment_tabletop(cloud, tabletop_options, context);
  const std::vector<std::uint8_t> mask = tabletop::tabletop_mask(segmented, cloud.size());
  std::vector<std::uint32_t> members;
  std::vector<std::uint32_t> slot_of(cloud.size(), tabletop::kNoVoxel);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (mask[i]) {
      slot_of[i] = static_cast<std::uint32_t>(members.size());
      members.push_back(static_cast<std::uint32_t>(i));
    }
  PointCloud sub = gather(cloud, members, options.use_cloud_normals);
  const double prefilter_seconds = seconds_since(start);
  context.throw_if_stopped("labeling");

  const LabelingResult partial = label_all_points(model, features, sub, options, context);
  LabelingResult result = fan_out(partial, sub, slot_of, cloud, options);
  // One point per slot: the sub-cloud's own count stands (fan_out counts copies).
  result.labeled_points = partial.labeled_points;
  result.prefilter_seconds = prefilter_seconds;
  if (options.want_objects) result.objects = tabletop::object_ids(segmented, cloud.size());
  return result;
}

// `input`: the caller's cloud when `cloud` is it (see label_distinct_points).
LabelingResult label_points(const LabelModel& model, const FeatureSettings& features,
                            PointCloud& cloud, const LabelingOptions& options,
                            const RunContext& context, const PointCloud* input = nullptr) {
  return options.tabletop_only ? label_tabletop(model, features, cloud, options, context)
                               : label_all_points(model, features, cloud, options, context, input);
}

// Voxel centroids, with the mean of the members' normals (normalised) when the cloud's own
// normals are used.
PointCloud voxel_cloud(const PointCloud& cloud, const tabletop::VoxelGrid& grid,
                       bool with_normals) {
  PointCloud voxels;
  voxels.resize_unorganized(grid.centroids.size());
  voxels.xyz = grid.centroids;
  voxels.viewpoint = cloud.viewpoint;
  if (!with_normals) return voxels;
  voxels.normals.assign(grid.centroids.size(), Vec3f::Constant(kNaN));
  for (std::size_t v = 0; v < grid.centroids.size(); ++v) {
    Vec3f sum = Vec3f::Zero();
    for (std::uint32_t m = grid.member_offsets[v]; m < grid.member_offsets[v + 1]; ++m) {
      const Vec3f& n = cloud.normals[grid.members[m]];
      if (is_finite(n)) sum += n;
    }
    if (sum.norm() > 0.0f) voxels.normals[v] = sum.normalized();
  }
  return voxels;
}

LabelingResult label_voxels(const LabelModel& model, const FeatureSettings& features,
                            PointCloud& cloud, float voxel_size, const LabelingOptions& options,
                            const RunContext& context) {
  const auto start = std::chrono::steady_clock::now();
  const tabletop::VoxelGrid grid = tabletop::voxel_downsample(
      cloud.xyz, tabletop::finite_indices(cloud.xyz), voxel_size, context);
  PointCloud voxels = voxel_cloud(cloud, grid, options.use_cloud_normals);
  const double voxel_seconds = seconds_since(start);
  context.throw_if_stopped("labeling");

  const LabelingResult partial = label_points(model, features, voxels, options, context);
  LabelingResult result = fan_out(partial, voxels, grid.voxel_of_point, cloud, options);
  result.prefilter_seconds = partial.prefilter_seconds + voxel_seconds;
  result.voxel_seconds = voxel_seconds;
  return result;
}

}  // namespace

LabelingResult label_cloud(const LabelModel& model, PointCloud& cloud,
                           const LabelingOptions& options, const RunContext& context) {
  if (options.use_cloud_normals && cloud.normals.size() != cloud.size())
    throw std::invalid_argument("use_cloud_normals: the cloud has " +
                                std::to_string(cloud.normals.size()) + " normals for " +
                                std::to_string(cloud.size()) + " points");
  validate(model, options);
  const FeatureSettings features = effective_features(model, options);
  const float voxel_size = effective_voxel_size(model, options);
  context.throw_if_stopped("labeling");
  LabelingResult result = voxel_size > 0.0f
                              ? label_voxels(model, features, cloud, voxel_size, options, context)
                              : label_points(model, features, cloud, options, context, &cloud);
  result.domain_warning =
      domain_warning(model.training, result.point_spacing, result.surface_variation);
  if (options.want_primitives && !result.primitives) {  // not fitted with the labeling's lists
    const auto start = std::chrono::steady_clock::now();
    result.primitives = primitives::fit_primitives(cloud.xyz, cloud.normals, result.labels,
                                                   options.primitives, context);
    result.primitive_seconds = seconds_since(start);
  }
  if (result.objects) {
    tabletop::describe_objects(cloud.xyz, *result.objects);
    if (result.primitives) {
      std::vector<std::size_t> segment_points;
      for (const primitives::Primitive& p : result.primitives->primitives)
        segment_points.push_back(p.points);
      tabletop::assign_primitives(result.primitives->point_segment, segment_points,
                                  *result.objects);
    }
  }
  return result;
}

}  // namespace primlabel::pipeline
