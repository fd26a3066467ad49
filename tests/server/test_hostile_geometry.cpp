// Hostile geometry against a real server on 127.0.0.1: far points (1e6 up to FLT_MAX) mixed with
// a normal scan, with and without voxels, 100k coincident points, 20k points packed into a 1 mm
// cube. Each request ends with a clear status in bounded time and memory, and the server goes on
// serving the next legitimate client with the same labels as before.

#include <cfloat>
#include <fstream>
#include <random>
#include <thread>

#include "proc_status.hpp"
#include "server_test_util.hpp"

namespace primlabel::servertest {
namespace {

using testing::random_label_model;
using testing::table_with_box_cloud;

// VmHWM of this process (the server runs in it), in MB.
double peak_rss_mb() { return double(testing::proc_status("VmHWM")) / 1024.0; }

PointCloud cloud_of(std::vector<Vec3f> points) {
  PointCloud cloud;
  cloud.resize_unorganized(points.size());
  cloud.xyz = std::move(points);
  return cloud;
}

// `n` points drawn uniformly from the cube [lo, hi)^3, shifted by `offset`.
std::vector<Vec3f> points_in_cube(std::size_t n, float lo, float hi, unsigned seed,
                                  const Vec3f& offset = Vec3f::Zero()) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> cube(lo, hi);
  std::vector<Vec3f> points(n);
  for (Vec3f& p : points) p = Vec3f(cube(rng), cube(rng), cube(rng)) + offset;
  return points;
}

class HostileGeometry : public ::testing::Test {
 protected:
  // A CRF model, so the graph and inference see the hostile points too.
  HostileGeometry()
      : model_(random_label_model("m", "1", 7, 0.5f)),
        server_({model_}),
        table_(table_with_box_cloud(0.01f)),
        reference_(reference_labels(model_, table_)) {}

  LabelAnswer send(const PointCloud& cloud, std::chrono::milliseconds deadline) {
    return label_stream(*server_.stub, scan_requests(cloud, header_for()), deadline);
  }

  // A hostile scan's answer, its wall time and how much it raised the peak RSS.
  struct Measured {
    LabelAnswer answer;
    double seconds = 0, peak_growth_mb = 0;
  };
  Measured send_measured(const PointCloud& cloud) {
    const double rss_before = peak_rss_mb();
    const auto start = std::chrono::steady_clock::now();
    Measured measured{send(cloud, std::chrono::seconds(60))};
    measured.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    measured.peak_growth_mb = peak_rss_mb() - rss_before;
    return measured;
  }

  // A hostile scan took under 30 s and 400 MB more peak memory, and the server goes on.
  void expect_bounded_and_still_serving(const Measured& measured) {
    EXPECT_LT(measured.seconds, 30.0);
    EXPECT_LT(measured.peak_growth_mb, 400.0);
    expect_still_serving();
  }

  // The server is alive and answers a legitimate scan exactly as before.
  void expect_still_serving() {
    EXPECT_EQ(health_status(server_.channel, "primlabel.v1.Labeler"), "SERVING");
    const LabelAnswer answer = send(table_, std::chrono::seconds(60));
    ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
    EXPECT_EQ(answer.labels, reference_);
  }

  LabelModel model_;
  TestServer server_;
  PointCloud table_;
  std::vector<std::uint32_t> reference_;
};

TEST_F(HostileGeometry, FarPointsMixedWithAScanGetAnAnswerAndTheScanKeepsItsLabels) {
  for (const float far : {1e18f, 1e30f, FLT_MAX, -FLT_MAX}) {
    SCOPED_TRACE(far);
    std::vector<Vec3f> points = table_.xyz;
    points.push_back({far, 0.0f, 0.0f});
    points.push_back({0.1f, far, -far});
    points.push_back({far, far, far});
    const PointCloud cloud = cloud_of(std::move(points));
    const LabelAnswer answer = send(cloud, std::chrono::seconds(60));
    ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
    ASSERT_EQ(answer.labels.size(), cloud.size());
    // The scan's own points see the same neighbourhoods as without the far ones.
    EXPECT_EQ(std::vector<std::uint32_t>(answer.labels.begin(),
                                         answer.labels.begin() + std::ptrdiff_t(table_.size())),
              reference_);
  }
  // A cloud of nothing but far points, far from each other.
  const LabelAnswer lonely =
      send(cloud_of({{1e18f, 0, 0}, {-1e30f, 1, 1}, {FLT_MAX, FLT_MAX, -FLT_MAX}}),
           std::chrono::seconds(60));
  EXPECT_TRUE(lonely.status.ok()) << lonely.status.error_message();
  expect_still_serving();
}

// The same far points against a model that downsamples (as the default LMS400 and Kinect
// models do): once "voxel leaf 0.003 is too small for the cloud's extent", INTERNAL. Now the far
// points are answered unknown and counted, and so are a leaf of 1e-30 and a 1e6 m cube.
// With shape evidence too: the table-top stage and the shape fitter see the far points as well.
LabelModel voxel_model(bool shape_evidence) {
  LabelModel model = random_label_model("voxels", "1", 7, 0.5f);
  model.features.voxel_size = 0.003f;
  if (shape_evidence) {
    model.features.shape_evidence = true;
    // The same weights and coupling, the evidence's columns 0.
    const crf::CrfModel narrow = model.weights;
    model.weights = crf::CrfModel::zeros(narrow.class_ids, model.features.model_input_dim());
    const Eigen::Index d = narrow.descriptor_dim;
    model.weights.node_weights.leftCols(d) = narrow.node_weights.leftCols(d);
    model.weights.node_weights.rightCols(1) = narrow.node_weights.rightCols(1);  // the bias
    model.weights.edge_weights.rightCols(1) = narrow.edge_weights.rightCols(1);
  }
  return model;
}

class HostileGeometryOnVoxels : public ::testing::TestWithParam<bool> {};
INSTANTIATE_TEST_SUITE_P(ShapeEvidence, HostileGeometryOnVoxels, ::testing::Bool());

TEST_P(HostileGeometryOnVoxels, FarPointsAnyLeafAndAHugeCubeAreAnsweredAndCounted) {
  const LabelModel model = voxel_model(GetParam());
  TestServer server({model});
  const PointCloud table = table_with_box_cloud(0.01f);
  const auto send = [&](const PointCloud& cloud, float voxel_size = 0.0f) {
    v1::ScanHeader header = header_for();
    header.mutable_options()->set_voxel_size(voxel_size);
    return label_stream(*server.stub, scan_requests(cloud, header), std::chrono::seconds(60));
  };
  const LabelAnswer plain = send(table);
  ASSERT_TRUE(plain.status.ok()) << plain.status.error_message();
  ASSERT_TRUE(plain.summary);
  EXPECT_EQ(plain.summary->points_isolated(), 0u);
  EXPECT_GT(plain.summary->points_labeled(), table.size() * 9 / 10);

  for (const float far : {1e6f, 1e18f, FLT_MAX}) {
    SCOPED_TRACE(far);
    std::vector<Vec3f> points = table.xyz;
    points.push_back({far, 0.0f, 0.0f});
    points.push_back({0.1f, -far, far});
    const LabelAnswer answer = send(cloud_of(std::move(points)));
    ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
    ASSERT_EQ(answer.labels.size(), table.size() + 2);
    EXPECT_EQ(answer.labels[table.size()], 0u);
    EXPECT_EQ(answer.labels[table.size() + 1], 0u);
    ASSERT_TRUE(answer.summary);
    EXPECT_EQ(answer.summary->points_isolated(), 2u);
    EXPECT_GT(answer.summary->points_labeled(), table.size() * 9 / 10);
  }

  const LabelAnswer tiny_leaf = send(table, 1e-30f);
  ASSERT_TRUE(tiny_leaf.status.ok()) << tiny_leaf.status.error_message();
  EXPECT_GT(tiny_leaf.summary->points_labeled(), table.size() * 9 / 10);

  const std::vector<Vec3f> spread = points_in_cube(100000, -5e5f, 5e5f, 4);
  const LabelAnswer huge = send(cloud_of(spread));
  ASSERT_TRUE(huge.status.ok()) << huge.status.error_message();
  EXPECT_EQ(huge.summary->points_isolated(), spread.size());
  EXPECT_EQ(huge.summary->points_labeled(), 0u);

  EXPECT_EQ(health_status(server.channel, "primlabel.v1.Labeler"), "SERVING");
}

TEST_F(HostileGeometry, OneHundredThousandCoincidentPointsAreBoundedInTimeAndMemory) {
  const Measured measured =
      send_measured(cloud_of(std::vector<Vec3f>(100000, Vec3f(0.1f, 0.2f, 0.3f))));
  const LabelAnswer& answer = measured.answer;
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  ASSERT_EQ(answer.labels.size(), 100000u);
  // Copies of one point are one point: every copy gets the same label.
  for (std::uint32_t label : answer.labels) ASSERT_EQ(label, answer.labels[0]);
  // Before duplicates were collapsed this cost 84 CPU-seconds and 1.1 GB.
  expect_bounded_and_still_serving(measured);
}

TEST_F(HostileGeometry, TwentyThousandPointsInAMillimetreCubeAreBounded) {
  const std::vector<Vec3f> points = points_in_cube(20000, 0.0f, 0.001f, 3, Vec3f(0, 0, 0.5f));
  const Measured measured = send_measured(cloud_of(points));
  ASSERT_TRUE(measured.answer.status.ok()) << measured.answer.status.error_message();
  EXPECT_EQ(measured.answer.labels.size(), points.size());
  expect_bounded_and_still_serving(measured);
}

TEST_F(HostileGeometry, ADeadlineOnAHeavyHostileScanFreesTheWorkerAtOnce) {
  const LabelAnswer answer =
      send(cloud_of(points_in_cube(1000000, 0.0f, 0.002f, 5)), std::chrono::milliseconds(1500));
  EXPECT_EQ(answer.status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED)
      << answer.status.error_message();
  // Counted as what it was: the client's deadline, not a cancel (the client's timer fires
  // before the server's copy of the deadline).
  const auto count = [&](const char* status) {
    return scrape::sum_samples(scrape_metrics(server_.server->metrics_port()),
                               "primlabel_requests_total",
                               {{"method", "Label"}, {"status", status}});
  };
  for (int i = 0; i < 100 && count("DEADLINE_EXCEEDED") < 1.0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(count("DEADLINE_EXCEEDED"), 1.0);
  EXPECT_EQ(count("CANCELLED"), 0.0);
  // The single worker is free again well before the stopped job could have finished.
  const auto start = std::chrono::steady_clock::now();
  expect_still_serving();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 20.0);
}

}  // namespace
}  // namespace primlabel::servertest
