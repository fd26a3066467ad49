// Primitive instances through the service (LabelOptions.return_primitives): the summary's
// primitives and the chunks' segment ids are exactly those of label_cloud in process, and on a
// model whose labels are known (every described point a plane) the table comes back as the
// plane z = 0.

#include <cmath>

#include "primitives/primitive_samples.hpp"
#include "primlabel/service/answer_size.hpp"
#include "server_test_util.hpp"

namespace primlabel::servertest {
namespace {

using testing::random_label_model;
using testing::table_with_box_cloud;

std::vector<std::uint32_t> segments_of(const LabelAnswer& answer) {
  std::vector<std::uint32_t> segments;
  for (const v1::LabelChunk& chunk : answer.chunks) {
    const std::size_t n = segments.size();
    EXPECT_EQ(chunk.segments().size(), 4u * chunk.point_count());
    segments.resize(n + chunk.segments().size() / 4);
    wire::unpack_le<std::uint32_t>(chunk.segments(), segments.data() + n);
  }
  return segments;
}

Eigen::Vector3d vec(const v1::Vec3d& v) { return {v.x(), v.y(), v.z()}; }

v1::ScanHeader primitives_header(const std::string& model) {
  v1::ScanHeader header = header_for(model);
  header.mutable_options()->set_return_primitives(true);
  header.mutable_options()->set_response_chunk_points(1000);
  return header;
}

TEST(ServicePrimitives, MatchLabelCloudInProcess) {
  const LabelModel model = random_label_model("m", "1", 7);
  TestServer server({model});
  const PointCloud cloud = table_with_box_cloud(0.005f);
  const LabelAnswer answer =
      label_stream(*server.stub, scan_requests(cloud, primitives_header("m"), 7000));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();

  PointCloud local = cloud;
  pipeline::LabelingOptions options;
  options.want_primitives = true;
  const pipeline::LabelingResult expected = pipeline::label_cloud(model, local, options);
  ASSERT_TRUE(expected.primitives);
  const auto& primitives = expected.primitives->primitives;
  ASSERT_GT(primitives.size(), 1u);
  EXPECT_EQ(answer.labels, expected.labels);
  EXPECT_EQ(segments_of(answer), expected.primitives->point_segment);

  const v1::LabelSummary& summary = *answer.summary;
  ASSERT_EQ(std::size_t(summary.primitives_size()), primitives.size());
  std::set<v1::PrimitiveKind> kinds;
  for (std::size_t s = 0; s < primitives.size(); ++s) {
    const primitives::Primitive& want = primitives[s];
    const v1::Primitive& got = summary.primitives(int(s));
    EXPECT_LE(got.ByteSizeLong(), service::kMaxPrimitiveMessageBytes) << s;
    kinds.insert(got.kind());
    EXPECT_EQ(got.segment_id(), s);
    EXPECT_EQ(std::uint32_t(got.kind()), std::uint32_t(want.kind())) << s;
    EXPECT_EQ(got.class_id(), want.class_id);
    EXPECT_EQ(got.point_count(), want.points);
    EXPECT_EQ(got.first_point(), want.first_point);
    EXPECT_EQ(got.inliers(), want.inliers);
    EXPECT_EQ(got.rms(), want.rms);
    EXPECT_EQ(got.confidence(), want.confidence);
    EXPECT_EQ(vec(got.centroid()), want.centroid);
    EXPECT_EQ(vec(got.bounds_min()), want.bounds_min);
    EXPECT_EQ(vec(got.bounds_max()), want.bounds_max);
    if (const auto* plane = std::get_if<primitives::PlaneModel>(&want.model)) {
      ASSERT_TRUE(got.has_plane()) << s;
      EXPECT_EQ(vec(got.plane().normal()), plane->normal);
      EXPECT_EQ(got.plane().offset(), plane->offset);
      EXPECT_EQ(vec(got.plane().center()), plane->center);
      EXPECT_EQ(vec(got.plane().axis_u()), plane->axis_u);
      EXPECT_EQ(got.plane().extent_v(), plane->extent_v);
    } else if (const auto* line = std::get_if<primitives::LineModel>(&want.model)) {
      ASSERT_TRUE(got.has_line()) << s;
      EXPECT_EQ(vec(got.line().direction()), line->direction);
      EXPECT_EQ(got.line().length(), line->length);
    } else if (const auto* cylinder = std::get_if<primitives::CylinderModel>(&want.model)) {
      ASSERT_TRUE(got.has_cylinder()) << s;
      EXPECT_EQ(vec(got.cylinder().axis()), cylinder->axis);
      EXPECT_EQ(got.cylinder().radius(), cylinder->radius);
    } else if (std::holds_alternative<std::monostate>(want.model)) {
      EXPECT_EQ(got.model_case(), v1::Primitive::MODEL_NOT_SET) << s;
    }
  }
  EXPECT_GE(kinds.size(), 2u);  // with these weights: an edge line and corner segments
  std::vector<std::string> stages;
  for (const auto& timing : summary.timings()) stages.push_back(timing.stage());
  EXPECT_EQ(stages, (std::vector<std::string>{"receive", "prefilter", "normals", "features",
                                              "inference", "primitives", "send"}));
}

// Labels known: the only class with weight is plane (its bias), so every described point is a
// plane. A 0.5 m table at z = 0 and, 0.2 m beside it, a standing cylinder: two segments.
TEST(ServicePrimitives, TheTableComesBackAsThePlaneZEqualsZero) {
  LabelModel model = random_label_model("planes", "1");
  model.weights = crf::CrfModel::zeros({1, 2}, kFpfhSize);
  model.weights.node_weights(0, model.weights.node_feature_dim() - 1) = 1.0f;
  TestServer server({model});

  PointCloud cloud;
  std::vector<Vec3f> points;
  const float spacing = 0.005f;
  for (int i = 0; i <= 100; ++i)
    for (int j = 0; j <= 100; ++j)
      points.emplace_back(-0.25f + i * spacing, -0.25f + j * spacing, 0);
  const std::size_t table_points = points.size();
  primitives::test::Samples can;
  primitives::test::SampleMaker maker(3);
  primitives::test::add_cylinder(can, maker, {0.5, 0, 0.01}, Eigen::Vector3d::UnitZ(), 0.04, 0.12,
                                 2 * M_PI, 3000);
  points.insert(points.end(), can.xyz.begin(), can.xyz.end());
  cloud.resize_unorganized(points.size());
  cloud.xyz = std::move(points);

  const LabelAnswer answer =
      label_stream(*server.stub, scan_requests(cloud, primitives_header("planes"), 5000));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  const v1::LabelSummary& summary = *answer.summary;
  ASSERT_EQ(summary.primitives_size(), 2);
  const v1::Primitive& table = summary.primitives(0);  // the largest segment first
  EXPECT_EQ(table.class_id(), 1u);
  EXPECT_EQ(table.point_count(), table_points);
  ASSERT_EQ(table.kind(), v1::PRIMITIVE_PLANE);
  ASSERT_TRUE(table.has_plane());
  EXPECT_NEAR(std::abs(table.plane().normal().z()), 1.0, 1e-6);
  EXPECT_NEAR(table.plane().offset(), 0.0, 0.001);
  EXPECT_NEAR(table.plane().extent_u(), 0.5, 0.01);
  EXPECT_NEAR(table.plane().extent_v(), 0.5, 0.01);
  EXPECT_EQ(table.inliers(), table_points);
  EXPECT_NEAR(table.confidence(), 1.0, 1e-9);
  EXPECT_NEAR(vec(table.centroid()).norm(), 0.0, 1e-4);
  EXPECT_EQ(summary.primitives(1).point_count(), can.xyz.size());
  EXPECT_NEAR(summary.primitives(1).centroid().x(), 0.5, 0.005);

  const std::vector<std::uint32_t> segments = segments_of(answer);
  ASSERT_EQ(segments.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    ASSERT_EQ(segments[i], i < table_points ? 0u : 1u) << i;
}

// Without the option nothing changes: no primitives, no segment ids, no stage.
TEST(ServicePrimitives, OnlyWhenAskedFor) {
  TestServer server({random_label_model("m", "1")});
  const PointCloud cloud = table_with_box_cloud(0.01f);
  const LabelAnswer answer = label_stream(*server.stub, scan_requests(cloud, header_for("m")));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.summary->primitives_size(), 0);
  for (const v1::LabelChunk& chunk : answer.chunks) EXPECT_TRUE(chunk.segments().empty());
  for (const auto& timing : answer.summary->timings()) EXPECT_NE(timing.stage(), "primitives");
}

}  // namespace
}  // namespace primlabel::servertest
