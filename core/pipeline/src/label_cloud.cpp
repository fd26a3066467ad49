// Labeling a cloud with a trained model, down once and back once: the plan says where every input
// point takes its answer from (voxels, the table-top stage, exact duplicates: labeling_plan.hpp);
// that one cloud is described with the model's settings (or allowed overrides), given its graph
// and inferred (CRF or node-only) or classified point by point (SVM); the answers go back to every
// input point (fan_out.hpp), whose labels then give the primitives and the objects.

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "fan_out.hpp"
#include "labeling_options.hpp"
#include "labeling_plan.hpp"
#include "multi_scale_input.hpp"
#include "primlabel/crf/inference.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/pipeline/crease_points.hpp"
#include "primlabel/pipeline/domain.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/svm_model.hpp"
#include "primlabel/tabletop/tabletop_objects.hpp"

namespace primlabel::pipeline {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void require_normal_per_point(const PointCloud& cloud, const LabelingOptions& options) {
  if (options.use_cloud_normals && cloud.normals.size() != cloud.size())
    throw std::invalid_argument("use_cloud_normals: the cloud has " +
                                std::to_string(cloud.normals.size()) + " normals for " +
                                std::to_string(cloud.size()) + " points");
}

// The primitives of the labeled input cloud, from its labels and the normals left in it. `shared`:
// the neighbour index, lists and point spacing that described this very cloud, if still alive.
void fit_primitives_of_input(const PointCloud& cloud, const LabelingOptions& options,
                             const RunContext& context, const primitives::SharedNeighbors& shared,
                             LabelingResult& result) {
  const auto start = std::chrono::steady_clock::now();
  result.primitives = primitives::fit_primitives(cloud.xyz, cloud.normals, result.labels,
                                                 options.primitives, context, shared);
  result.seconds.primitives = seconds_since(start);
}

// The plane cascade's points (described.cascaded) labeled plane. Their probabilities: the mean
// row of the points the model itself labeled plane in this cloud (one-hot plane when it labeled
// none), so they say how sure the model is of this scene's planes, not more.
void label_cascaded_planes(const std::vector<std::uint8_t>& cascaded,
                           const LabelingOptions& options, LabelingResult& result) {
  const std::uint32_t plane = class_id(PrimitiveClass::kPlane);
  const std::vector<std::uint32_t>& ids = result.class_ids;
  const auto column = std::find(ids.begin(), ids.end(), plane);
  if (column == ids.end()) return;  // a model without planes: no cascade (label_described)
  if (options.want_probabilities) {
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(result.probabilities.cols());
    std::size_t counted = 0;
    for (std::size_t i = 0; i < cascaded.size(); ++i)
      if (!cascaded[i] && result.labels[i] == plane) {
        mean += result.probabilities.row(Eigen::Index(i)).transpose().cast<double>();
        ++counted;
      }
    if (counted > 0) {
      mean /= double(counted);
    } else {
      mean.setZero();
      mean(column - ids.begin()) = 1.0;
    }
    const Eigen::RowVectorXf row = mean.transpose().cast<float>();
    for (std::size_t i = 0; i < cascaded.size(); ++i)
      if (cascaded[i]) result.probabilities.row(Eigen::Index(i)) = row;
  }
  for (std::size_t i = 0; i < cascaded.size(); ++i)
    if (cascaded[i]) {
      result.labels[i] = plane;
      ++result.cascaded_points;
    }
  result.labeled_points += result.cascaded_points;
}

// What the crease decision needs of the described cloud once it is labeled (crease_points.hpp).
struct SlotIndex {
  std::unique_ptr<NeighborSearch> search;  // over the described cloud
  std::vector<std::uint8_t> inferred;      // per point: the CRF labeled it; empty: no marginals
};

// Every point of `cloud` described and labeled, one row per point. `is_input`: `cloud` is the
// caller's cloud itself, so wanted primitives are fitted here, while the description's neighbour
// index and lists are alive to be reused. `slot_index` (may be null): asks for the CRF's
// marginals (in result.probabilities, even unless wanted) and keeps the index and the inferred
// points there for the crease decision.
LabelingResult label_described(const LabelModel& model, const FeatureSettings& features,
                               PointCloud& cloud, const LabelingOptions& options,
                               const RunContext& context, bool is_input, SlotIndex* slot_index) {
  LabelingResult result;
  result.class_ids = model.class_ids();
  DescribeOptions describe_options;
  describe_options.use_cloud_normals = options.use_cloud_normals;
  describe_options.share_neighbor_lists = options.share_neighbor_lists;
  // A model without a plane class has no label for the cascade's points: they are described.
  const bool has_planes = std::find(result.class_ids.begin(), result.class_ids.end(),
                                    class_id(PrimitiveClass::kPlane)) != result.class_ids.end();
  describe_options.plane_cascade = options.plane_cascade && !options.want_descriptors && has_planes;
  describe_options.trained_roughness = model.training.roughness_max;
  describe_options.trained_surface_variation = model.training.surface_variation_max;
  DescribedCloud described = describe_cloud(cloud, features, describe_options, context);
  result.seconds = described.seconds;
  result.described_points = cloud.size();
  result.point_spacing = described.point_spacing;
  result.surface_variation = described.surface_variation;
  context.throw_if_stopped("labeling");
  if (model.kind == ModelKind::kSvm) {  // point by point: no graph
    const std::vector<std::uint8_t> cascaded = std::move(described.cascaded);
    classify_with_svm(model, std::move(described), options, context, result);
    label_cascaded_planes(cascaded, options, result);
    return result;
  }

  const auto start = std::chrono::steady_clock::now();
  crf::GraphSettings graph_options = model.graph;
  // A node-only model ignores edges, so its graph needs none (only the active mask).
  if (model.kind == ModelKind::kNodeOnly) graph_options.neighborhood = Neighborhood::Knn(1);
  const crf::Graph graph = build_scene_graph(cloud, described, graph_options, context);
  result.seconds.graph = seconds_since(start);
  context.throw_if_stopped("labeling");
  const auto inference_start = std::chrono::steady_clock::now();
  crf::InferenceOutputs outputs;
  outputs.unknown_label = class_id(PrimitiveClass::kUnknown);
  outputs.marginals = options.want_probabilities || slot_index;
  crf::InferenceResult inferred =
      infer(model.weights, described.descriptors, graph, model.inference, outputs, context);
  result.seconds.inference = seconds_since(inference_start);

  result.labels = std::move(inferred.labels);
  if (outputs.marginals) result.probabilities = std::move(inferred.marginals);
  if (options.want_descriptors)
    result.descriptors =
        leading_values(std::move(described.descriptors), model.features.descriptor_dim());
  result.labeled_points = graph.num_active();
  label_cascaded_planes(described.cascaded, options, result);
  if (options.want_primitives && is_input)
    fit_primitives_of_input(
        cloud, options, context,
        {described.search.get(), described.lists.get(), described.point_spacing}, result);
  if (slot_index) {
    slot_index->search = std::move(described.search);
    slot_index->inferred = graph.active;  // not the cascade's points, whose rows are not the CRF's
  }
  return result;
}

std::size_t isolated_points(const PointCloud& cloud, const LabelingPlan& plan,
                            const std::vector<std::uint32_t>& labels) {
  const std::uint32_t unknown = class_id(PrimitiveClass::kUnknown);
  std::size_t isolated = 0;
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (labels[i] == unknown && is_finite(cloud.xyz[i]) &&
        (plan.in_place || plan.slot_of[i] != kNoSlot))
      ++isolated;
  return isolated;
}

// The objects' counts and shapes from the input points' coordinates and ids, and the primitives
// lying in each.
void describe_objects_of_input(const PointCloud& cloud, LabelingResult& result) {
  tabletop::describe_objects(cloud.xyz, *result.objects);
  if (!result.primitives) return;
  std::vector<std::size_t> segment_points;
  for (const primitives::Primitive& p : result.primitives->primitives)
    segment_points.push_back(p.points);
  tabletop::assign_primitives(result.primitives->point_segment, segment_points, *result.objects);
}

}  // namespace

LabelingResult label_cloud(const LabelModel& model, PointCloud& cloud,
                           const LabelingOptions& options, const RunContext& context) {
  require_normal_per_point(cloud, options);
  validate(model, options);
  const FeatureSettings features = effective_features(model, options);
  context.throw_if_stopped("labeling");

  // Down once: the one cloud to describe, and every input point's slot in it.
  LabelingPlan plan = plan_labeling(cloud, effective_voxel_size(model, options), options, context);
  PointCloud& described = plan.described_cloud(cloud);
  // Points decided on their own near creases need voxels and the CRF's marginals.
  const bool creases = options.crease_points && plan.voxel_size > 0.0f;
  SlotIndex slot_index;
  LabelingResult result =
      label_described(model, features, described, options, context,
                      /*is_input=*/plan.in_place, creases ? &slot_index : nullptr);
  result.seconds.voxels = plan.seconds.voxels;
  result.seconds.tabletop = plan.seconds.tabletop;
  result.seconds.duplicates = plan.seconds.duplicates;
  result.domain_warning =
      domain_warning(model.training, result.point_spacing, result.surface_variation);
  if (sparser_than_trained(model.training, result.point_spacing)) {
    const std::string units = units_hint(model.training, cloud, context);
    if (!units.empty()) result.domain_warning = units + "; " + result.domain_warning;
  }

  // Back once: every input point gets its slot's answer; primitives and objects are the input's.
  if (!plan.in_place) {
    std::optional<CreaseAnswers> crease;
    if (!slot_index.inferred.empty()) {
      const auto start = std::chrono::steady_clock::now();
      crease = decide_crease_points(cloud.xyz, plan.slot_of,
                                    {&described.xyz, slot_index.search.get(), slot_index.inferred,
                                     result.labels, &result.probabilities, result.class_ids},
                                    plan.voxel_size, context);
      result.seconds.fanout += seconds_since(start);
    }
    fan_out(plan, described, options, cloud, result, crease ? &*crease : nullptr);
  }
  if (options.want_primitives && !result.primitives)
    fit_primitives_of_input(cloud, options, context, {}, result);
  if (plan.objects) {
    result.objects = std::move(plan.objects);
    describe_objects_of_input(cloud, result);
  }
  result.isolated_points = isolated_points(cloud, plan, result.labels);
  return result;
}

}  // namespace primlabel::pipeline
