#pragma once
// The glue from a point cloud to per-point primitive labels: normals and descriptors with a
// model's feature settings, the CRF's neighbourhood graph, training scenes from labeled clouds,
// and labeling a cloud with a trained LabelModel.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/training.hpp"
#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/descriptors.hpp"
#include "primlabel/geometry/neighbor_lists.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/stage_seconds.hpp"
#include "primlabel/primitives/fit_primitives.hpp"
#include "primlabel/tabletop/tabletop_objects.hpp"

namespace primlabel::pipeline {

// Normals (written into the cloud) and descriptors of every point, plus the neighbour index that
// computed them so the graph can reuse it. `search` indexes cloud.xyz: keep the cloud alive and
// unmoved while it is used.
struct DescribedCloud {
  Descriptors descriptors;  // one row per point; NaN rows = invalid
  std::unique_ptr<NeighborSearch> search;
  // One radius search per point at the larger of the normal and feature radii, shared by
  // normals, descriptors and the graph (null when the neighbourhoods are not both radii).
  std::unique_ptr<NeighborLists> lists;
  StageSeconds seconds;         // its index, lists, normals, cascade and descriptors
  float point_spacing = 0;      // median_point_spacing of the described cloud (m; NaN: none)
  float surface_variation = 0;  // median_surface_variation of its normals (NaN: its own normals)
  // With DescribeOptions::plane_cascade: 1 for the points the plane cascade labels plane
  // (their descriptor rows are NaN); empty otherwise.
  std::vector<std::uint8_t> cascaded;
};

// Thrown by describe_cloud and label_cloud when their stop token is requested.
using Cancelled = primlabel::Cancelled;

// A radius neighbourhood without a cap (max_neighbors 0) gets this one wherever the pipeline
// describes a cloud or builds its graph, for training and labeling alike: the nearest 1024 within
// the radius. Each point then costs a bounded amount whatever the input (points packed into a
// millimetre cost O(n * 1024), not O(n^2)). The cap lies well above what the default scenes hold
// within their radii, so their features are unchanged by it.
inline constexpr int kDefaultMaxNeighbors = 1024;
// `hood` with kDefaultMaxNeighbors when it is a radius neighbourhood without a cap; a model's own
// cap and k-nearest neighbourhoods are kept.
Neighborhood capped(const Neighborhood& hood);

struct DescribeOptions {
  // Keep cloud.normals (one per point, e.g. from the sensor) instead of estimating them.
  bool use_cloud_normals = false;
  // Search once at the larger radius and share the lists (DescribedCloud::lists). Off: every
  // stage searches itself (the same neighbours; FPFH sums them in another order, so descriptors
  // differ in rounding). For benchmarks and tests that compare the two.
  bool share_neighbor_lists = true;
  // The plane cascade (LabelingOptions::plane_cascade), bounded by the noise of the model's
  // training scans (TrainingSummary::roughness_max, else surface_variation_max). Needs estimated
  // normals, radius neighbourhoods and FPFH of the cloud's own points: ignored otherwise.
  bool plane_cascade = false;
  float trained_roughness = 0.0f;
  float trained_surface_variation = 0.0f;
};

// Throws std::invalid_argument for settings describe_cloud cannot honour (voxel downsampling:
// label_cloud does it) or a missing normal per point with use_cloud_normals, and Cancelled when
// context.stop is requested (checked per point and inside the index builds).
DescribedCloud describe_cloud(PointCloud& cloud, const FeatureSettings& settings,
                              const DescribeOptions& options, const RunContext& context = {});
DescribedCloud describe_cloud(PointCloud& cloud, const FeatureSettings& settings,
                              const RunContext& context = {});

crf::Graph build_scene_graph(const PointCloud& cloud, const DescribedCloud& described,
                             const crf::GraphSettings& settings, const RunContext& context = {});

// A training / validation scene: labels become class indices into `class_ids`; taxonomy ids that
// are not one of the model's classes (kUnknown included) become kIgnoreLabel.
crf::LabeledGraph to_labeled_graph(const PointCloud& cloud, DescribedCloud&& described,
                                   crf::Graph graph, const std::vector<std::uint32_t>& class_ids);

struct LabelingOptions {
  bool want_probabilities = false;
  bool want_descriptors = false;  // LabelingResult.descriptors
  bool tabletop_only = false;     // label only the table and the objects on it; the rest is unknown
  // Keep the cloud's own normals (cloud.normals, one per point) instead of estimating them.
  bool use_cloud_normals = false;
  // > 0: downsample to voxels of this edge before describing (replaces the model's voxel_size);
  // every input point gets its voxel's label, probabilities, descriptor and normal (near creases,
  // with crease_points, its own label and probabilities).
  float voxel_size = 0.0f;
  // > 0: replace the model's normal / feature radius. Only for models whose FeatureSettings
  // allow it (radii_overridable), else label_cloud throws std::invalid_argument.
  float normal_radius = 0.0f;
  float feature_radius = 0.0f;
  bool share_neighbor_lists = true;  // DescribeOptions::share_neighbor_lists
  // Also group the labels into connected segments and fit each with its class's primitive
  // (LabelingResult::primitives), from the labels and the normals label_cloud leaves in the cloud.
  bool want_primitives = false;
  primitives::PrimitiveOptions primitives;
  // With tabletop_only: the table and its objects as instances, every input point's object id
  // and, with want_primitives, the primitives of each (LabelingResult::objects).
  bool want_objects = false;
  // The plane cascade: points whose neighbourhood is planar within the scene's plane noise are
  // labeled plane without a descriptor or a CRF node (far fewer points to describe and infer on
  // a table-top scene); those within the feature radius of a point that is not planar are
  // described and inferred as before. Their probabilities are the mean of the points the model
  // labeled plane. Off with want_descriptors or use_cloud_normals (every point is then
  // described), for models that recorded no surface variation of their training scenes, and
  // for models without a plane class. The service turns it on unless a request asks for
  // every_point.
  bool plane_cascade = false;
  // With voxels (voxel_size or the model's), for CRF and node-only models: an input point whose
  // voxel has a described neighbour voxel with another label (a crease cuts through it) is
  // labeled at its own position, from the CRF marginals of the nearest described voxels weighted
  // by inverse squared distance (crease_points.hpp); its probabilities are those interpolated
  // ones. Every other point keeps its voxel's answer, the cascade's planes theirs. Off by
  // default: +0.1-0.2 points on Kinect frames for tens of ms a frame (results.md).
  bool crease_points = false;
};

struct LabelingResult {
  std::vector<std::uint32_t> labels;  // taxonomy class id per point; 0 (unknown) when unlabeled
  Eigen::MatrixXf probabilities;      // points x K (model class order) when asked; NaN rows
  std::vector<std::uint32_t> class_ids;
  // One row per point when asked (else empty, dim 0); NaN rows = the point had no descriptor.
  Descriptors descriptors;
  std::size_t labeled_points = 0;    // input points that got a descriptor (through their voxel)
  std::size_t described_points = 0;  // points described: voxels when downsampling
  std::size_t cascaded_points = 0;   // of those, labeled plane by the plane cascade
  // Input points with finite coordinates left unknown because nothing lies within the model's
  // radii of them (a far outlier, a lonely return): they could not be described. Points the
  // table-top stage leaves out are not counted.
  std::size_t isolated_points = 0;
  StageSeconds seconds;         // where the time went, stage by stage
  float point_spacing = 0;      // median point spacing of the described cloud (m)
  float surface_variation = 0;  // median surface variation of its computed normals
  // Not empty when point_spacing is far outside what the model was trained for (domain.hpp):
  // the labels are then unreliable, and the caller should be told so.
  std::string domain_warning;
  // With want_primitives: the fitted instances and every point's segment (primitive) id.
  std::optional<primitives::PrimitiveSet> primitives;
  // With want_objects: the table, the objects and every input point's object id.
  std::optional<tabletop::TabletopObjects> objects;
};

// What label_cloud cannot honour in its options, by option, so that a service can tell its
// client in the client's own terms: a voxel size or radius below 0 or not finite, invalid
// primitive options, objects without the table-top stage (whatever the model), and radius
// overrides the model does not allow (the second form).
enum class RefusedOption { kVoxelSize, kRadius, kPrimitives, kObjects, kRadiusOverride };
struct OptionsRefusal {
  RefusedOption option;
  std::string reason;  // in LabelingOptions' terms
};
std::optional<OptionsRefusal> refusal(const LabelingOptions& options);
std::optional<OptionsRefusal> refusal(const LabelModel& model, const LabelingOptions& options);

// The same as std::invalid_argument(reason). label_cloud checks it before any work; a service
// checks refusal() as soon as it has the options, so what label_cloud throws later is never the
// caller's fault.
void validate(const LabelingOptions& options);
void validate(const LabelModel& model, const LabelingOptions& options);

// Labels every point with the model's own feature, graph and inference settings (and the
// overrides in `options`). Points with non-finite coordinates or no descriptor get class 0.
// Exact duplicates are described once (duplicates.hpp): every copy gets the labels,
// probabilities, descriptor and normal of its lowest-index copy.
// Throws ModelError when an SVM model's libsvm text does not load, std::invalid_argument for
// options validate() refuses or a missing normal per point with use_cloud_normals, and
// Cancelled when context.stop is requested (checked between stages and per point inside them, the
// table-top stage, the voxel filter and the index builds included: within milliseconds). The labels
// (and primitives) do not depend on context.threads.
LabelingResult label_cloud(const LabelModel& model, PointCloud& cloud,
                           const LabelingOptions& options = {}, const RunContext& context = {});

}  // namespace primlabel::pipeline
