// Normals and descriptors with a model's FeatureSettings; the neighbour index is built once and
// shared by normals, descriptors and the graph.

#include <algorithm>
#include <chrono>
#include <limits>
#include <optional>
#include <stdexcept>

#include "multi_scale_input.hpp"
#include "plane_cascade.hpp"
#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/normals.hpp"
#include "primlabel/geometry/point_spacing.hpp"
#include "primlabel/pipeline/feature_sample.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/shape_evidence.hpp"

namespace primlabel::pipeline {

namespace {
double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

namespace {
// Memory for the shared neighbour lists (8 bytes a neighbour): a 300k-point frame at ~100
// neighbours fits; beyond it points are searched again per stage, as without the lists.
constexpr std::size_t kSharedListBytes = std::size_t(256) << 20;
// Lists longer than this on average cost more to store and filter than the searches they save
// (a dense LMS400 scan has ~500 points within 25 mm; a 5 mm voxel frame ~150 within 30 mm).
constexpr double kMaxSharedListLength = 256;

// Whether sharing pays: the mean list length over an even sample of the points, and the lists
// of every point within the budget.
bool sharing_pays(const std::vector<Vec3f>& points, const NeighborSearch& search,
                  const Neighborhood& hood) {
  constexpr std::size_t kSample = 256;
  const std::size_t stride = std::max<std::size_t>(1, points.size() / kSample);
  NeighborList found;
  std::size_t sampled = 0, entries = 0;
  for (std::size_t i = 0; i < points.size(); i += stride) {
    if (!is_finite(points[i])) continue;
    search.find(points[i], hood, found, /*sorted=*/false);
    ++sampled, entries += found.size();
  }
  if (sampled == 0) return false;
  const double mean = double(entries) / double(sampled);
  return mean <= kMaxSharedListLength &&
         mean * double(points.size()) * 8.0 <= double(kSharedListBytes);
}

// The neighbourhood that holds both (radius or hybrid) neighbourhoods, or none.
std::optional<Neighborhood> shared_neighborhood(const Neighborhood& a, const Neighborhood& b) {
  if (!(a.radius > 0.0f) || !(b.radius > 0.0f)) return std::nullopt;
  const int cap = (a.max_neighbors == 0 || b.max_neighbors == 0)
                      ? 0
                      : std::max(a.max_neighbors, b.max_neighbors);
  return Neighborhood{std::max(a.radius, b.radius), 0, cap};
}
}  // namespace

Neighborhood capped(const Neighborhood& hood) {
  Neighborhood out = hood;
  if (out.radius > 0.0f && out.max_neighbors == 0) out.max_neighbors = kDefaultMaxNeighbors;
  return out;
}

DescribedCloud describe_cloud(PointCloud& cloud, const FeatureSettings& settings,
                              const RunContext& context) {
  return describe_cloud(cloud, settings, DescribeOptions{}, context);
}

DescribedCloud describe_cloud(PointCloud& cloud, const FeatureSettings& settings,
                              const DescribeOptions& options, const RunContext& context) {
  if (settings.voxel_size > 0.0f)
    throw std::invalid_argument("describe_cloud does not downsample: label_cloud does");
  if (!settings.normals.valid() || !settings.features.valid())
    throw std::invalid_argument("invalid normal or feature neighbourhood");
  if (options.use_cloud_normals && cloud.normals.size() != cloud.size())
    throw std::invalid_argument("the cloud has no normal per point to keep");
  context.throw_if_stopped("describing the cloud");
  DescribedCloud out;
  const auto index_start = std::chrono::steady_clock::now();
  // The index build checks the token itself (a 5M-point k-d tree takes about a second).
  out.search = std::make_unique<NeighborSearch>(cloud.xyz, context.stop);
  out.point_spacing = median_point_spacing(cloud.xyz, *out.search);
  out.seconds.index = seconds_since(index_start);
  // The stages' own progress counts (points, then twice the points for FPFH) would not add up to
  // one describe call: only threads and stop go down.
  const RunContext stage{context.threads, context.stop, {}};
  const Neighborhood normal_hood = capped(settings.normals);
  const Neighborhood feature_hood = capped(settings.features);
  const bool fpfh = settings.descriptor == DescriptorKind::kFpfh;
  // A sampled FPFH searches the sample, not the cloud: only normals and the graph share lists.
  const bool sampled = fpfh && settings.feature_sample_size > 0.0f;
  const std::optional<Neighborhood> shared =
      sampled ? (options.use_cloud_normals ? std::nullopt
                                           : shared_neighborhood(normal_hood, normal_hood))
              : shared_neighborhood(options.use_cloud_normals ? feature_hood : normal_hood,
                                    feature_hood);
  const auto lists_start = std::chrono::steady_clock::now();
  if (shared && options.share_neighbor_lists && fpfh &&
      sharing_pays(cloud.xyz, *out.search, *shared)) {
    out.lists =
        std::make_unique<NeighborLists>(cloud.xyz, *out.search, *shared, kSharedListBytes, stage);
    out.seconds.lists = seconds_since(lists_start);
  }

  if (!options.use_cloud_normals) {
    const auto start = std::chrono::steady_clock::now();
    NormalOptions normal_options;
    normal_options.neighborhood = normal_hood;
    estimate_normals(cloud, normal_options, stage, out.search.get(), out.lists.get());
    out.seconds.normals = seconds_since(start);
    out.surface_variation = median_surface_variation(cloud.curvature);
  } else {
    out.surface_variation = std::numeric_limits<float>::quiet_NaN();  // the client's normals
  }
  // The plane cascade: only the points it leaves to the CRF are described (FPFH of the cloud's
  // own points alone can describe a subset).
  std::vector<std::uint8_t> wanted;
  if (options.plane_cascade && !options.use_cloud_normals && fpfh && !sampled &&
      normal_hood.radius > 0.0f && feature_hood.radius > 0.0f) {
    const auto cascade_start = std::chrono::steady_clock::now();
    const CascadeScale scale{std::max(normal_hood.radius, feature_hood.radius),
                             normal_hood.radius >= feature_hood.radius};
    // At the normal radius the normals' own curvature is the variation: no copy, no search.
    std::vector<float> measured;
    if (!scale.is_normal_radius)
      measured = surface_variations(cloud.xyz, scale.radius, *out.search, out.lists.get(), stage);
    const std::vector<float>& variation = scale.is_normal_radius ? cloud.curvature : measured;
    const CascadeNoise noise{options.trained_roughness, options.trained_surface_variation};
    const float max_variation =
        cascade_max_variation(median_surface_variation(variation), noise, scale);
    out.cascaded = cascaded_planes(cloud, variation, max_variation, feature_hood.radius,
                                   *out.search, out.lists.get(), stage);
    wanted.resize(out.cascaded.size());
    for (std::size_t i = 0; i < wanted.size(); ++i) wanted[i] = out.cascaded[i] ? 0 : 1;
    if (std::find(wanted.begin(), wanted.end(), 0) == wanted.end()) wanted.clear();  // none
    out.seconds.cascade = seconds_since(cascade_start);
  }

  const auto start = std::chrono::steady_clock::now();
  FeatureOptions feature_options;
  feature_options.neighborhood = feature_hood;
  feature_options.fpfh_variant = settings.fpfh_variant;
  feature_options.wanted = wanted;
  if (sampled) {
    // Every point described against the sample's points (same indices as the cloud).
    const std::vector<Vec3f> sample = voxel_sample(cloud.xyz, settings.feature_sample_size, stage);
    const NeighborSearch sample_search(sample, context.stop);
    out.descriptors = compute_fpfh(cloud, feature_options, stage, {.search = &sample_search});
  } else {
    out.descriptors =
        fpfh ? compute_fpfh(cloud, feature_options, stage,
                            {.search = out.search.get(), .lists = out.lists.get()})
             : compute_pfh(cloud, feature_options, stage, {.search = out.search.get()});
  }
  out.descriptors = multi_scale_input(cloud, std::move(out.descriptors), settings, *out.search,
                                      !options.use_cloud_normals, wanted, stage);
  out.seconds.descriptors = seconds_since(start);
  if (settings.shape_evidence) {
    const auto shapes_start = std::chrono::steady_clock::now();
    out.descriptors =
        with_shape_evidence(cloud, std::move(out.descriptors), stage, out.search.get());
    out.seconds.shapes = seconds_since(shapes_start);
  }
  return out;
}

crf::Graph build_scene_graph(const PointCloud& cloud, const DescribedCloud& described,
                             const crf::GraphSettings& settings, const RunContext& context) {
  crf::GraphSettings bounded = settings;
  bounded.neighborhood = capped(settings.neighborhood);
  return crf::build_graph(cloud.xyz, described.descriptors, bounded, context,
                          described.search.get(), described.lists.get());
}

crf::LabeledGraph to_labeled_graph(const PointCloud& cloud, DescribedCloud&& described,
                                   crf::Graph graph, const std::vector<std::uint32_t>& class_ids) {
  if (cloud.labels.size() != cloud.size())
    throw std::invalid_argument("the cloud has no label per point");
  crf::LabeledGraph scene;
  scene.descriptors = std::move(described.descriptors);
  scene.graph = std::move(graph);
  scene.labels.assign(cloud.size(), crf::kIgnoreLabel);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!scene.graph.active[i]) continue;  // no descriptor: nothing to learn from
    for (std::size_t k = 0; k < class_ids.size(); ++k)
      if (class_ids[k] == cloud.labels[i]) scene.labels[i] = static_cast<int>(k);
  }
  return scene;
}

}  // namespace primlabel::pipeline
