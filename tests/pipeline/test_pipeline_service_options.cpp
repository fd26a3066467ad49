// label_cloud options the labeling service exposes: descriptors out, client normals, radius
// overrides, voxel downsampling, per-stage timings and cancellation.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <stop_token>
#include <thread>

#include "primlabel/geometry/normals.hpp"
#include "primlabel/pipeline/duplicates.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/primitives/primitives_json.hpp"
#include "primlabel/tabletop/voxel_grid.hpp"
#include "random_label_model.hpp"

namespace primlabel {
namespace {

using testing::random_label_model;
using testing::table_with_box_cloud;

TEST(PipelineServiceOptions, DescriptorsAreReturnedRowMajorAsDescribeComputesThem) {
  const LabelModel model = random_label_model();
  PointCloud cloud = table_with_box_cloud();
  pipeline::LabelingOptions options;
  options.want_descriptors = true;
  const auto result = pipeline::label_cloud(model, cloud, options);
  ASSERT_EQ(result.descriptors.dim, kFpfhSize);
  ASSERT_EQ(result.descriptors.size(), cloud.size());
  // The fixture samples the box's edges twice: label_cloud describes each position once (at its
  // lowest index) and gives every copy that row, so compare with describe_cloud on the distinct
  // points.
  PointCloud again = table_with_box_cloud();
  const pipeline::DuplicateMap duplicates = pipeline::find_duplicates(again.xyz);
  ASSERT_TRUE(duplicates.any());
  PointCloud distinct;
  distinct.resize_unorganized(duplicates.representatives.size());
  distinct.viewpoint = again.viewpoint;
  for (std::size_t j = 0; j < distinct.size(); ++j)
    distinct.xyz[j] = again.xyz[duplicates.representatives[j]];
  const auto described = pipeline::describe_cloud(distinct, model.features);
  for (std::size_t i = 0; i < result.descriptors.values.size(); ++i) {
    const std::size_t row = duplicates.slot_of[i / kFpfhSize], bin = i % kFpfhSize;
    const float a = result.descriptors.values[i], b = described.descriptors.row(row)[bin];
    ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << "value " << i;
  }
  EXPECT_TRUE(pipeline::label_cloud(model, again, {}).descriptors.empty());
}

TEST(PipelineServiceOptions, TimingsAreSeparatePerStage) {
  PointCloud cloud = table_with_box_cloud();
  const auto start = std::chrono::steady_clock::now();
  const auto result = pipeline::label_cloud(random_label_model(), cloud, {});
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const pipeline::StageSeconds& seconds = result.seconds;
  for (double ran : {seconds.duplicates, seconds.index, seconds.normals, seconds.descriptors,
                     seconds.graph, seconds.inference, seconds.fanout})
    EXPECT_GT(ran, 0.0);
  for (double skipped : {seconds.voxels, seconds.tabletop, seconds.primitives})
    EXPECT_EQ(skipped, 0.0);
  // Each second in one stage only: together they cannot exceed the call.
  EXPECT_LE(seconds.total(), wall);
  // Every distinct position is described once (the fixture repeats the box's edges).
  EXPECT_EQ(result.described_points, pipeline::find_duplicates(cloud.xyz).representatives.size());
  EXPECT_LT(result.described_points, cloud.size());
}

// One radius search shared by normals, FPFH and the graph (5 mm spacing: ~80 points within the
// 25 mm feature radius): the same normals and graph as each stage searching itself, descriptors
// equal up to summation order, the same labels, and the same for 1 and 2 threads.
TEST(PipelineServiceOptions, SharedNeighbourListsChangeNothingButTheSearches) {
  const LabelModel model = random_label_model("crf", "1", 7, 0.5f);
  pipeline::LabelingOptions shared_options, own_options;
  shared_options.want_descriptors = own_options.want_descriptors = true;
  own_options.share_neighbor_lists = false;
  PointCloud shared_cloud = table_with_box_cloud(0.005f), own_cloud = shared_cloud;
  const auto shared = pipeline::label_cloud(model, shared_cloud, shared_options, RunContext{1});
  const auto own = pipeline::label_cloud(model, own_cloud, own_options, RunContext{1});
  EXPECT_GT(shared.seconds.lists, 0.0);
  EXPECT_EQ(own.seconds.lists, 0.0);
  // Too dense to pay (hundreds of points within the radius): each stage searches itself.
  PointCloud dense = table_with_box_cloud(0.002f);
  EXPECT_EQ(pipeline::label_cloud(model, dense, shared_options, RunContext{2}).seconds.lists, 0.0);
  ASSERT_EQ(shared.descriptors.values.size(), own.descriptors.values.size());
  std::size_t normals_off = 0;
  for (std::size_t i = 0; i < shared_cloud.size(); ++i)
    if (!(shared_cloud.normals[i] - own_cloud.normals[i]).isZero(1e-5f)) ++normals_off;
  EXPECT_EQ(normals_off, 0u);
  float worst = 0.0f;
  for (std::size_t i = 0; i < own.descriptors.values.size(); ++i) {
    const float a = shared.descriptors.values[i], b = own.descriptors.values[i];
    ASSERT_EQ(std::isnan(a), std::isnan(b)) << i;
    if (!std::isnan(a)) worst = std::max(worst, std::abs(a - b));
  }
  EXPECT_LT(worst, 1e-3f);  // bins sum to 100 per sub-histogram
  std::size_t differ = 0;
  for (std::size_t i = 0; i < own.labels.size(); ++i) differ += shared.labels[i] != own.labels[i];
  EXPECT_LE(differ, own.labels.size() / 1000);
  PointCloud again = table_with_box_cloud(0.005f);
  EXPECT_EQ(pipeline::label_cloud(model, again, shared_options, RunContext{2}).labels,
            shared.labels);
}

// label_cloud fits the primitives with the index, lists and spacing that described the cloud;
// they are those of fit_primitives on its labels and normals alone, bit for bit, at 1 and 2
// threads (and the lists were there to share).
TEST(PipelineServiceOptions, PrimitivesFromTheSharedListsAreThoseOfAStandaloneFit) {
  const LabelModel model = random_label_model("crf", "1", 7, 0.5f);
  pipeline::LabelingOptions options;
  options.want_primitives = true;
  for (int threads : {1, 2}) {
    PointCloud cloud = table_with_box_cloud(0.005f);
    const auto labeled = pipeline::label_cloud(model, cloud, options, RunContext{threads});
    EXPECT_GT(labeled.seconds.lists, 0.0);
    ASSERT_TRUE(labeled.primitives);
    const primitives::PrimitiveSet alone = primitives::fit_primitives(
        cloud.xyz, cloud.normals, labeled.labels, options.primitives, RunContext{threads});
    ASSERT_GE(alone.primitives.size(), 1u);
    EXPECT_EQ(labeled.primitives->segment_radius, alone.segment_radius);
    EXPECT_EQ(labeled.primitives->point_segment, alone.point_segment);
    EXPECT_EQ(primitives::primitives_json(labeled.primitives->primitives),
              primitives::primitives_json(alone.primitives));
  }
}

TEST(PipelineServiceOptions, ClientNormalsSkipEstimationAndGiveTheSameLabels) {
  const LabelModel model = random_label_model();
  PointCloud estimated = table_with_box_cloud();
  const auto reference = pipeline::label_cloud(model, estimated, {});

  PointCloud supplied = table_with_box_cloud();
  supplied.normals = estimated.normals;  // as a sensor driver would send them
  pipeline::LabelingOptions options;
  options.use_cloud_normals = true;
  const auto result = pipeline::label_cloud(model, supplied, options);
  EXPECT_EQ(result.labels, reference.labels);
  EXPECT_EQ(result.seconds.normals, 0.0);

  PointCloud none = table_with_box_cloud();
  EXPECT_THROW(pipeline::label_cloud(model, none, options), std::invalid_argument);
}

TEST(PipelineServiceOptions, RadiusOverridesOnlyWhenTheModelAllowsThem) {
  LabelModel model = random_label_model();
  pipeline::LabelingOptions options;
  options.want_descriptors = true;
  options.feature_radius = 0.05f;
  PointCloud cloud = table_with_box_cloud();
  EXPECT_THROW(pipeline::label_cloud(model, cloud, options), std::invalid_argument);

  model.features.radii_overridable = true;
  const auto wider = pipeline::label_cloud(model, cloud, options);
  PointCloud again = table_with_box_cloud();
  options.feature_radius = 0.0f;
  const auto own = pipeline::label_cloud(model, again, options);
  EXPECT_NE(wider.descriptors, own.descriptors);
}

// One check of the options, before any work, that a service can also run before the cloud comes.
TEST(PipelineServiceOptions, ValidateRefusesWhatLabelCloudRefuses) {
  LabelModel model = random_label_model();
  const auto refused = [&](const pipeline::LabelingOptions& options) {
    EXPECT_THROW(pipeline::validate(model, options), std::invalid_argument);
    PointCloud cloud = table_with_box_cloud();
    EXPECT_THROW(pipeline::label_cloud(model, cloud, options), std::invalid_argument);
  };
  pipeline::LabelingOptions options;
  EXPECT_NO_THROW(pipeline::validate(model, options));
  options.voxel_size = -0.01f;
  refused(options);
  options.voxel_size = std::numeric_limits<float>::infinity();
  refused(options);
  options = {};
  options.want_primitives = true;
  options.primitives.segments.min_points = 0;
  refused(options);
  options = {};
  options.want_objects = true;
  refused(options);
  options.tabletop_only = true;
  EXPECT_NO_THROW(pipeline::validate(model, options));
  options = {};
  options.normal_radius = 0.02f;
  refused(options);
  model.features.radii_overridable = true;
  EXPECT_NO_THROW(pipeline::validate(model, options));
}

// feature_sample_size: every point keeps its own descriptor, computed against one point per
// voxel, so descriptors change but stay close to the full ones; the same for any thread count.
TEST(PipelineServiceOptions, SampledFpfhDescribesEveryPointAgainstOnePointPerVoxel) {
  LabelModel model = random_label_model();
  pipeline::LabelingOptions options;
  options.want_descriptors = true;
  PointCloud full_cloud = table_with_box_cloud(0.0025f);
  const auto full = pipeline::label_cloud(model, full_cloud, options, RunContext{2});
  model.features.feature_sample_size = 0.005f;
  PointCloud cloud = table_with_box_cloud(0.0025f);
  const auto sampled = pipeline::label_cloud(model, cloud, options, RunContext{1});
  ASSERT_EQ(sampled.labels.size(), cloud.size());
  EXPECT_EQ(sampled.described_points, full.described_points);  // no point loses its descriptor
  ASSERT_EQ(sampled.descriptors.values.size(), full.descriptors.values.size());
  EXPECT_NE(sampled.descriptors.values, full.descriptors.values);
  // Each sub-histogram still sums to 100 (PCL's normalisation), and rows stay near the full ones.
  double mean_l1 = 0.0;
  std::size_t rows = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const float* a = &sampled.descriptors.values[i * kFpfhSize];
    const float* b = &full.descriptors.values[i * kFpfhSize];
    if (std::isnan(a[0]) || std::isnan(b[0])) continue;
    float sum = 0.0f;
    for (int k = 0; k < kFpfhBinsPerFeature; ++k) sum += a[k];
    if (sum == 0.0f) continue;  // isolated: zero rows in both
    ASSERT_NEAR(sum, 100.0f, 0.05f) << i;
    double l1 = 0.0;
    for (int k = 0; k < kFpfhSize; ++k) l1 += std::fabs(double(a[k]) - double(b[k]));
    mean_l1 += l1, ++rows;
  }
  ASSERT_GT(rows, cloud.size() / 2);
  EXPECT_LT(mean_l1 / double(rows), 60.0);  // of 300: the same surfaces, a sparser sample
  PointCloud again = table_with_box_cloud(0.0025f);
  const auto two_threads = pipeline::label_cloud(model, again, options, RunContext{2});
  EXPECT_EQ(two_threads.labels, sampled.labels);
  EXPECT_EQ(two_threads.descriptors.values, sampled.descriptors.values);
}

TEST(PipelineServiceOptions, VoxelDownsamplingGivesEveryPointItsVoxelsResults) {
  const LabelModel model = random_label_model();
  PointCloud cloud = table_with_box_cloud(0.0025f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.xyz[3] = Vec3f(nan, 0.0f, 0.0f);
  pipeline::LabelingOptions options;
  options.voxel_size = 0.005f;
  options.want_descriptors = true;
  options.want_probabilities = true;
  options.crease_points = false;  // the default, said here: the test is of per-voxel answers
  const auto result = pipeline::label_cloud(model, cloud, options, RunContext{1});
  ASSERT_EQ(result.labels.size(), cloud.size());
  ASSERT_EQ(result.probabilities.rows(), Eigen::Index(cloud.size()));
  ASSERT_EQ(result.descriptors.values.size(), cloud.size() * kFpfhSize);
  EXPECT_LT(result.described_points, cloud.size() / 2);
  EXPECT_EQ(result.labels[3], 0u);
  EXPECT_TRUE(std::isnan(result.probabilities(3, 0)));

  // Points of one voxel share everything.
  const auto grid = tabletop::voxel_downsample(cloud.xyz, tabletop::finite_indices(cloud.xyz),
                                               options.voxel_size);
  std::size_t checked = 0;
  for (std::size_t v = 0; v < grid.centroids.size(); ++v) {
    const std::uint32_t first = grid.members[grid.member_offsets[v]];
    for (std::uint32_t m = grid.member_offsets[v] + 1; m < grid.member_offsets[v + 1]; ++m) {
      const std::uint32_t i = grid.members[m];
      ASSERT_EQ(result.labels[i], result.labels[first]);
      ASSERT_EQ(result.probabilities(i, 1), result.probabilities(first, 1));
      ++checked;
    }
  }
  EXPECT_GT(checked, cloud.size() / 2);
  EXPECT_GT(result.labeled_points, cloud.size() / 2);

  // Same labels for any thread count.
  PointCloud again = table_with_box_cloud(0.0025f);
  again.xyz[3] = cloud.xyz[3];
  EXPECT_EQ(pipeline::label_cloud(model, again, options, RunContext{2}).labels, result.labels);
}

TEST(PipelineServiceOptions, AStoppedTokenCancelsBeforeAnyWork) {
  std::stop_source source;
  source.request_stop();
  const RunContext context{0, source.get_token()};
  PointCloud cloud = table_with_box_cloud();
  EXPECT_THROW(pipeline::label_cloud(random_label_model(), cloud, {}, context),
               pipeline::Cancelled);
}

TEST(PipelineServiceOptions, StoppingFromAnotherThreadCancelsInsideTheStages) {
  // A CRF on a dense cloud; stop it at a few points in time and expect either a result (it was
  // faster) or Cancelled, never anything else, and the same labels as usual when it completes.
  const LabelModel model = random_label_model("crf", "1", 7, 0.5f);
  PointCloud reference_cloud = table_with_box_cloud(0.003f);
  const auto reference = pipeline::label_cloud(model, reference_cloud, {});
  int cancelled = 0;
  for (int delay_ms : {0, 10, 40}) {
    std::stop_source source;
    const RunContext context{0, source.get_token()};
    PointCloud cloud = table_with_box_cloud(0.003f);
    std::jthread stopper([&source, delay_ms] {
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
      source.request_stop();
    });
    try {
      EXPECT_EQ(pipeline::label_cloud(model, cloud, {}, context).labels, reference.labels);
    } catch (const pipeline::Cancelled&) {
      ++cancelled;
    }
  }
  EXPECT_GE(cancelled, 1);
}

TEST(PipelineServiceOptions, InferenceHonoursItsStopToken) {
  PointCloud cloud = table_with_box_cloud();
  const LabelModel model = random_label_model("crf", "1", 7, 0.5f);
  const auto described = pipeline::describe_cloud(cloud, model.features);
  const auto graph = pipeline::build_scene_graph(cloud, described, model.graph);
  std::stop_source source;
  source.request_stop();
  RunContext stopped;
  stopped.stop = source.get_token();
  EXPECT_THROW(
      crf::infer(model.weights, described.descriptors, graph, model.inference, {}, stopped),
      Cancelled);
  EXPECT_EQ(crf::infer(model.weights, described.descriptors, graph, model.inference).labels.size(),
            cloud.size());
}

TEST(PipelineServiceOptions, StoppedTokensCancelTheIndexAndTheGraph) {
  PointCloud cloud = table_with_box_cloud();
  const LabelModel model = random_label_model("crf", "1", 7, 0.5f);
  std::stop_source source;
  source.request_stop();
  RunContext stopped;
  stopped.stop = source.get_token();
  EXPECT_THROW(pipeline::describe_cloud(cloud, model.features, stopped), Cancelled);
  const auto described = pipeline::describe_cloud(cloud, model.features);
  EXPECT_THROW(pipeline::build_scene_graph(cloud, described, model.graph, stopped), Cancelled);
}

TEST(PipelineServiceOptions, ANeverStoppedTokenGivesTheSameResult) {
  const LabelModel model = random_label_model("crf", "1", 7, 0.5f);
  pipeline::LabelingOptions options;
  options.want_probabilities = true;
  PointCloud reference_cloud = table_with_box_cloud(0.003f);
  const auto reference = pipeline::label_cloud(model, reference_cloud, options, RunContext{1});
  std::stop_source never;
  PointCloud cloud = table_with_box_cloud(0.003f);
  const auto result =
      pipeline::label_cloud(model, cloud, options, RunContext{2, never.get_token()});
  EXPECT_EQ(result.labels, reference.labels);
  ASSERT_EQ(result.probabilities.size(), reference.probabilities.size());
  EXPECT_EQ(std::memcmp(result.probabilities.data(), reference.probabilities.data(),
                        sizeof(float) * std::size_t(result.probabilities.size())),
            0);
}

}  // namespace
}  // namespace primlabel
