// Hostile inputs to label_cloud (issue 13): far points, coincident points, points packed into a
// millimetre cube, exact duplicates; bounded memory, stop latency and thread-count determinism.

#include <gtest/gtest.h>

#include <cfloat>
#include <chrono>
#include <fstream>
#include <limits>
#include <random>
#include <stop_token>
#include <string>
#include <thread>

#include "one_and_two_threads.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/pipeline/duplicates.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "proc_status.hpp"
#include "random_label_model.hpp"

namespace primlabel {
namespace {

using pipeline::LabelingOptions;
using pipeline::LabelingResult;

std::size_t peak_rss_bytes() { return std::size_t(testing::proc_status("VmHWM")) * 1024; }

PointCloud with_points(PointCloud cloud, const std::vector<Vec3f>& extra) {
  cloud.xyz.insert(cloud.xyz.end(), extra.begin(), extra.end());
  cloud.width = static_cast<std::uint32_t>(cloud.xyz.size());  // unorganised, as it was
  return cloud;
}

// The box-on-a-table fixture without its own duplicates (the box's edges are sampled twice).
PointCloud distinct_table() {
  const PointCloud table = testing::table_with_box_cloud(0.01f);
  const pipeline::DuplicateMap map = pipeline::find_duplicates(table.xyz);
  PointCloud out;
  out.resize_unorganized(map.representatives.size());
  out.viewpoint = table.viewpoint;
  for (std::size_t j = 0; j < out.size(); ++j) out.xyz[j] = table.xyz[map.representatives[j]];
  return out;
}

PointCloud coincident_cloud(std::size_t copies) {
  return with_points(distinct_table(), std::vector<Vec3f>(copies, Vec3f(0.05f, 0.2f, 0.0f)));
}

PointCloud packed_cube_cloud(std::size_t points) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> mm(0.0f, 0.001f);
  std::vector<Vec3f> cube(points);
  for (Vec3f& p : cube) p = Vec3f(0.2f + mm(rng), 0.2f + mm(rng), mm(rng));
  return with_points(distinct_table(), cube);
}

// A labeling's result with its wall time and how much it raised the peak RSS.
struct MeasuredLabeling {
  LabelingResult result;
  double seconds = 0;
  std::size_t peak_growth_bytes = 0;
};
MeasuredLabeling label_measured(const LabelModel& model, PointCloud& cloud,
                                const LabelingOptions& options) {
  const std::size_t before = peak_rss_bytes();
  const auto start = std::chrono::steady_clock::now();
  MeasuredLabeling measured{pipeline::label_cloud(model, cloud, options, RunContext{2})};
  measured.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  measured.peak_growth_bytes = peak_rss_bytes() - before;
  return measured;
}

LabelingOptions all_outputs() {
  LabelingOptions options;
  options.want_probabilities = true;
  options.want_descriptors = true;
  return options;
}

void expect_same_point(const LabelingResult& r, std::size_t a, std::size_t b) {
  EXPECT_EQ(r.labels[a], r.labels[b]) << a << " vs " << b;
  const auto pa = r.probabilities.row(Eigen::Index(a)), pb = r.probabilities.row(Eigen::Index(b));
  for (Eigen::Index k = 0; k < pa.size(); ++k)
    if (!(std::isnan(pa(k)) && std::isnan(pb(k)))) EXPECT_EQ(pa(k), pb(k));
  const std::size_t d = std::size_t(r.descriptors.dim);
  for (std::size_t f = 0; f < d; ++f) {
    const float x = r.descriptors.values[a * d + f], y = r.descriptors.values[b * d + f];
    if (!(std::isnan(x) && std::isnan(y))) ASSERT_EQ(x, y) << a << " vs " << b << " bin " << f;
  }
}

TEST(PipelineHostile, FarPointsAmongANormalScanLabelWithoutThrowing) {
  const LabelModel model = testing::random_label_model("far", "1", 7, 0.25f);
  for (const float far : {1e18f, 1e30f, FLT_MAX}) {
    const PointCloud normal = distinct_table();
    PointCloud cloud = with_points(normal, {Vec3f(far, far, far), Vec3f(-far, 0.0f, 0.0f),
                                            Vec3f(0.0f, far, -far), Vec3f(far, far, far)});
    LabelingResult result;
    ASSERT_NO_THROW(result = pipeline::label_cloud(model, cloud, all_outputs(), RunContext{2}))
        << far;
    ASSERT_EQ(result.labels.size(), cloud.size());
    // The scan itself is still labeled; the far points have no neighbours (unknown).
    EXPECT_GE(result.labeled_points, normal.size() * 9 / 10) << far;
    for (std::size_t i = normal.size(); i < cloud.size(); ++i)
      EXPECT_EQ(result.labels[i], class_id(PrimitiveClass::kUnknown))
          << far << " point " << i - normal.size() << " normal " << cloud.normals[i].transpose()
          << " fpfh[0] " << result.descriptors.row(i)[0];
  }
}

// Once an error ("voxel leaf 0.01 is too small for the cloud's extent"), which a server had to
// answer INTERNAL: real scans carry far outliers. Now the far point is a voxel of its own, labeled
// unknown and counted isolated, and the table is labeled as usual.
TEST(PipelineHostile, FarPointsWithVoxelsAreLabeledUnknownAndCounted) {
  const LabelModel model = testing::random_label_model();
  LabelingOptions options = all_outputs();
  options.voxel_size = 0.01f;
  PointCloud table = distinct_table();
  const LabelingResult plain = pipeline::label_cloud(model, table, options);
  for (const float far : {1e6f, FLT_MAX, -FLT_MAX}) {
    SCOPED_TRACE(far);
    PointCloud cloud = with_points(distinct_table(), {Vec3f(far, 0, 0), Vec3f(0, far, far)});
    const LabelingResult result = pipeline::label_cloud(model, cloud, options);
    ASSERT_EQ(result.labels.size(), cloud.size());
    EXPECT_EQ(result.labels[cloud.size() - 1], class_id(PrimitiveClass::kUnknown));
    EXPECT_EQ(result.labels[cloud.size() - 2], class_id(PrimitiveClass::kUnknown));
    // Counted: the far two and the table's own lonely voxels (a far point moves the grid's
    // origin from the cloud's corner to 0, so the table's voxels may differ a little).
    std::size_t table_unknown = 0;
    for (std::size_t i = 0; i + 2 < cloud.size(); ++i)
      table_unknown += result.labels[i] == class_id(PrimitiveClass::kUnknown) ? 1 : 0;
    EXPECT_EQ(result.isolated_points, table_unknown + 2);
    EXPECT_GT(result.labeled_points, plain.labeled_points * 9 / 10);
  }
}

TEST(PipelineHostile, CoincidentPointsLabelInBoundedMemoryAndFanOut) {
  const LabelModel model = testing::random_label_model("dup", "1", 7, 0.25f);
  PointCloud cloud = coincident_cloud(100000);
  const std::size_t first_copy = cloud.size() - 100000;
  const auto [result, seconds, growth] = label_measured(model, cloud, all_outputs());
  std::printf("100k coincident points: %.2f s, peak RSS +%.0f MB\n", seconds, growth / 1e6);
  EXPECT_LT(growth, std::size_t(400) << 20);  // 1.1 GB before the caps
  // Described once: every copy is labeled (it lies on the table) exactly as the first one.
  EXPECT_EQ(result.described_points, first_copy + 1);
  EXPECT_NE(result.labels[first_copy], class_id(PrimitiveClass::kUnknown));
  for (std::size_t i = first_copy + 1; i < cloud.size(); i += 997) {
    expect_same_point(result, first_copy, i);
    EXPECT_EQ(cloud.normals[i], cloud.normals[first_copy]);
  }
}

TEST(PipelineHostile, PointsPackedInAMillimetreCubeLabelInBoundedMemory) {
  const LabelModel model = testing::random_label_model("cube", "1", 7, 0.25f);
  PointCloud cloud = packed_cube_cloud(20000);
  const auto [result, seconds, growth] = label_measured(model, cloud, all_outputs());
  std::printf(
      "20k points in a 1 mm cube: %.2f s (normals %.2f, descriptors %.2f, inference %.2f), peak "
      "RSS +%.0f MB\n",
      seconds, result.seconds.normals, result.seconds.descriptors,
      result.seconds.graph + result.seconds.inference, growth / 1e6);
  EXPECT_LT(growth, std::size_t(400) << 20);
  EXPECT_EQ(result.labels.size(), cloud.size());
}

TEST(PipelineHostile, DuplicatesGetTheirFirstCopysResultsAndChangeNothingElse) {
  const LabelModel model = testing::random_label_model("copies", "1", 11, 0.25f);
  PointCloud plain = distinct_table();
  const std::size_t n = plain.size();
  std::vector<Vec3f> copies;
  std::vector<std::size_t> original;
  for (std::size_t i = 0; i < n; i += 7)
    for (int c = 0; c < 3; ++c) copies.push_back(plain.xyz[i]), original.push_back(i);
  ASSERT_EQ(plain.xyz[1].z(), 0.0f);                                   // a table point
  copies.push_back(Vec3f(plain.xyz[1].x(), plain.xyz[1].y(), -0.0f));  // -0 equals +0
  original.push_back(1);
  PointCloud cloud = with_points(plain, copies);

  const pipeline::DuplicateMap map = pipeline::find_duplicates(cloud.xyz);
  ASSERT_EQ(map.representatives.size(), n);
  for (std::size_t j = 0; j < n; ++j) ASSERT_EQ(map.representatives[j], j);

  const LabelingResult alone = pipeline::label_cloud(model, plain, all_outputs(), RunContext{2});
  const LabelingResult with_copies =
      pipeline::label_cloud(model, cloud, all_outputs(), RunContext{2});
  ASSERT_EQ(with_copies.labels.size(), cloud.size());
  // Counted per input point, copies included.
  std::size_t labeled = 0;
  for (std::uint32_t label : with_copies.labels)
    labeled += label != class_id(PrimitiveClass::kUnknown);
  EXPECT_EQ(with_copies.labeled_points, labeled);
  EXPECT_GT(labeled, alone.labeled_points);
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_EQ(with_copies.labels[i], alone.labels[i]) << i;
    ASSERT_EQ(cloud.normals[i], plain.normals[i]) << i;
  }
  for (std::size_t c = 0; c < original.size(); ++c) {
    expect_same_point(with_copies, original[c], n + c);
    ASSERT_EQ(cloud.normals[n + c], cloud.normals[original[c]]);
  }
  EXPECT_EQ(map.representatives[map.slot_of[cloud.size() - 1]], 1u);
}

TEST(PipelineHostile, DuplicatesAmongSomePointsAreThoseOfThosePointsGathered) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // Point 5 is point 2 with -0 (equal); points 0 and 6 are not among `some`.
  const std::vector<Vec3f> xyz = {Vec3f(0, 0, 0),   Vec3f(1, 0, 0), Vec3f(0, 0, 0),
                                  Vec3f(nan, 0, 0), Vec3f(1, 0, 0), Vec3f(-0.0f, 0, 0),
                                  Vec3f(2, 0, 0)};
  const std::vector<std::uint32_t> some = {1, 2, 3, 4, 5};
  std::vector<Vec3f> gathered;
  for (std::uint32_t i : some) gathered.push_back(xyz[i]);
  const pipeline::DuplicateMap among = pipeline::find_duplicates(xyz, some);
  const pipeline::DuplicateMap alone = pipeline::find_duplicates(gathered);
  EXPECT_EQ(among.representatives, alone.representatives);
  EXPECT_EQ(among.slot_of, alone.slot_of);
  // Positions in `some`: the first copy of each position, the NaN point its own.
  EXPECT_EQ(among.representatives, (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(among.slot_of, (std::vector<std::uint32_t>{0, 1, 2, 0, 1}));
}

TEST(PipelineHostile, HostileMixIsTheSameForOneAndTwoThreads) {
  const LabelModel model = testing::random_label_model("mix", "1", 5, 0.25f);
  PointCloud base = packed_cube_cloud(3000);
  base = with_points(base, std::vector<Vec3f>(2000, Vec3f(-0.2f, 0.25f, 0.0f)));
  base = with_points(base, {Vec3f(1e30f, 0, 0), Vec3f(FLT_MAX, FLT_MAX, FLT_MAX)});
  const auto [r1, r2] = testing::label_with_one_and_two_threads(model, base, all_outputs());
  ASSERT_EQ(r1.labels, r2.labels);
  ASSERT_EQ(r1.descriptors.values.size(), r2.descriptors.values.size());
  for (std::size_t k = 0; k < r1.descriptors.values.size(); ++k)
    if (!(std::isnan(r1.descriptors.values[k]) && std::isnan(r2.descriptors.values[k])))
      ASSERT_EQ(r1.descriptors.values[k], r2.descriptors.values[k]) << k;
}

// Stops label_cloud at a few moments and returns the worst latency from the stop to the return.
double worst_stop_latency_ms(const LabelModel& model, const PointCloud& input,
                             const LabelingOptions& base) {
  double worst = 0.0;
  for (const int delay_ms : {1, 20, 80, 250}) {
    PointCloud cloud = input;
    std::stop_source source;
    const RunContext context{2, source.get_token()};
    std::chrono::steady_clock::time_point stopped_at{};
    std::jthread stopper([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
      stopped_at = std::chrono::steady_clock::now();
      source.request_stop();
    });
    try {
      pipeline::label_cloud(model, cloud, base, context);
    } catch (const Cancelled&) {
    }
    const auto returned = std::chrono::steady_clock::now();
    stopper.join();
    if (returned > stopped_at)
      worst =
          std::max(worst, std::chrono::duration<double, std::milli>(returned - stopped_at).count());
  }
  return worst;
}

TEST(PipelineHostile, AStopIsHonouredQuicklyOnHostileInputs) {
  const LabelModel model = testing::random_label_model("stop", "1", 7, 0.25f);
  LabelingOptions options = all_outputs();
  const double coincident = worst_stop_latency_ms(model, coincident_cloud(100000), options);
  const double cube = worst_stop_latency_ms(model, packed_cube_cloud(20000), options);
  options.tabletop_only = true;
  const double tabletop = worst_stop_latency_ms(model, packed_cube_cloud(20000), options);
  std::printf("worst stop latency: coincident %.1f ms, cube %.1f ms, table-top %.1f ms\n",
              coincident, cube, tabletop);
  // Generous (a loaded CI machine); the benchmark shows the 100 ms target.
  EXPECT_LT(coincident, 2000.0);
  EXPECT_LT(cube, 2000.0);
  EXPECT_LT(tabletop, 2000.0);
}

}  // namespace
}  // namespace primlabel
