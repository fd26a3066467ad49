// Table-top objects through the service (LabelOptions.return_objects): the summary's table and
// objects and the chunks' object ids are exactly those of label_cloud in process, streamed and
// unary; refused without tabletop_only; nothing without the option.

#include "primlabel/service/answer_size.hpp"
#include "server_test_util.hpp"
#include "tabletop_objects_scene.hpp"

namespace primlabel::servertest {
namespace {

std::vector<std::uint32_t> objects_of(const LabelAnswer& answer) {
  std::vector<std::uint32_t> ids;
  for (const v1::LabelChunk& chunk : answer.chunks) {
    const std::size_t n = ids.size();
    EXPECT_EQ(chunk.objects().size(), 4u * chunk.point_count());
    ids.resize(n + chunk.objects().size() / 4);
    wire::unpack_le<std::uint32_t>(chunk.objects(), ids.data() + n);
  }
  return ids;
}

Eigen::Vector3d vec(const v1::Vec3d& v) { return {v.x(), v.y(), v.z()}; }

// Every described point a plane, so each object is one segment.
LabelModel all_planes_model() {
  LabelModel model = testing::random_label_model("planes", "1");
  model.weights = crf::CrfModel::zeros({1, 2}, kFpfhSize);
  model.weights.node_weights(0, model.weights.node_feature_dim() - 1) = 1.0f;
  return model;
}

v1::ScanHeader objects_header(const PointCloud& cloud, bool primitives = true) {
  v1::ScanHeader header = header_for("planes");
  header.mutable_viewpoint()->set_x(cloud.viewpoint.origin.x());
  header.mutable_viewpoint()->set_y(cloud.viewpoint.origin.y());
  header.mutable_viewpoint()->set_z(cloud.viewpoint.origin.z());
  header.mutable_options()->set_tabletop_only(true);
  header.mutable_options()->set_return_objects(true);
  header.mutable_options()->set_return_primitives(primitives);
  header.mutable_options()->set_response_chunk_points(5000);
  return header;
}

void expect_summary_matches(const v1::LabelSummary& summary,
                            const tabletop::TabletopObjects& want) {
  ASSERT_TRUE(want.table);
  ASSERT_TRUE(summary.has_table());
  const v1::TabletopTable& table = summary.table();
  EXPECT_EQ(vec(table.normal()), want.table->plane.head<3>().cast<double>());
  EXPECT_EQ(table.offset(), double(want.table->plane[3]));
  ASSERT_EQ(std::size_t(table.hull_size()), want.table->hull.size());
  for (int v = 0; v < table.hull_size(); ++v)
    EXPECT_EQ(vec(table.hull(v)), want.table->hull[std::size_t(v)].cast<double>());
  EXPECT_EQ(table.point_count(), want.table->points);
  EXPECT_EQ(std::vector<std::uint32_t>(table.primitive_ids().begin(), table.primitive_ids().end()),
            want.table->primitive_ids);
  EXPECT_LE(table.ByteSizeLong(), service::kMaxTableMessageBytes);
  ASSERT_EQ(std::size_t(summary.objects_size()), want.objects.size());
  for (std::size_t k = 0; k < want.objects.size(); ++k) {
    const v1::TabletopObject& got = summary.objects(int(k));
    const tabletop::TabletopObject& o = want.objects[k];
    EXPECT_EQ(got.object_id(), o.id);
    EXPECT_EQ(got.object_id(), k + 1);
    EXPECT_EQ(got.point_count(), o.points);
    EXPECT_EQ(vec(got.centroid()), o.centroid);
    EXPECT_EQ(vec(got.bounds_min()), o.bounds_min);
    EXPECT_EQ(vec(got.bounds_max()), o.bounds_max);
    EXPECT_EQ(got.height(), o.height);
    EXPECT_EQ(std::vector<std::uint32_t>(got.primitive_ids().begin(), got.primitive_ids().end()),
              o.primitive_ids);
    v1::TabletopObject without_ids = got;
    without_ids.clear_primitive_ids();
    EXPECT_LE(without_ids.ByteSizeLong(), service::kMaxObjectMessageBytes);
  }
}

TEST(ServiceObjects, MatchLabelCloudInProcess) {
  const LabelModel model = all_planes_model();
  TestServer server({model});
  const PointCloud cloud = testing::in_camera_frame(testing::objects_scene(0.005f, 0.02f));
  const v1::ScanHeader header = objects_header(cloud);

  PointCloud local = cloud;
  local.normals.clear();
  pipeline::LabelingOptions options;
  options.tabletop_only = true;
  options.want_objects = true;
  options.want_primitives = true;
  const pipeline::LabelingResult expected = pipeline::label_cloud(model, local, options);
  ASSERT_TRUE(expected.objects && expected.primitives);
  ASSERT_EQ(expected.objects->objects.size(), 3u);
  for (const auto& object : expected.objects->objects) EXPECT_EQ(object.primitive_ids.size(), 1u);

  for (const bool unary : {false, true}) {
    SCOPED_TRACE(unary ? "LabelCloud" : "Label");
    const LabelAnswer answer = unary
                                   ? label_cloud(*server.stub, cloud, header)
                                   : label_stream(*server.stub, scan_requests(cloud, header, 7000));
    ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
    EXPECT_EQ(answer.labels, expected.labels);
    EXPECT_EQ(objects_of(answer), expected.objects->point_object);
    ASSERT_TRUE(answer.summary);
    EXPECT_EQ(std::size_t(answer.summary->primitives_size()),
              expected.primitives->primitives.size());
    EXPECT_TRUE(answer.summary->no_table_reason().empty());
    expect_summary_matches(*answer.summary, *expected.objects);
  }
}

TEST(ServiceObjects, RefusedWithoutTabletopOnlyNamingTheOption) {
  TestServer server({all_planes_model()});
  const PointCloud cloud = testing::in_camera_frame(testing::objects_scene(0.01f));
  v1::ScanHeader header = objects_header(cloud);
  header.mutable_options()->set_tabletop_only(false);
  for (const bool unary : {false, true}) {
    const LabelAnswer answer = unary ? label_cloud(*server.stub, cloud, header)
                                     : label_stream(*server.stub, scan_requests(cloud, header));
    EXPECT_EQ(answer.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(answer.status.error_message().find("return_objects"), std::string::npos)
        << answer.status.error_message();
    EXPECT_NE(answer.status.error_message().find("tabletop_only"), std::string::npos);
  }
}

TEST(ServiceObjects, NoTableSaysWhyAndNothingWithoutTheOption) {
  TestServer server({all_planes_model()});
  // A vertical wall only: the camera's up finds no horizontal table.
  PointCloud wall;
  std::vector<Vec3f> points;
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 60; ++j) points.emplace_back(i * 0.005f, j * 0.005f, 1.0f);
  wall.resize_unorganized(points.size());
  wall.xyz = points;
  const LabelAnswer answer =
      label_stream(*server.stub, scan_requests(wall, objects_header(wall, false)));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_FALSE(answer.summary->has_table());
  EXPECT_FALSE(answer.summary->no_table_reason().empty());
  EXPECT_EQ(answer.summary->objects_size(), 0);
  for (std::uint32_t id : objects_of(answer)) EXPECT_EQ(id, tabletop::kNoObject);

  const PointCloud cloud = testing::in_camera_frame(testing::objects_scene(0.01f));
  v1::ScanHeader plain = objects_header(cloud, false);
  plain.mutable_options()->set_return_objects(false);
  const LabelAnswer without = label_stream(*server.stub, scan_requests(cloud, plain));
  ASSERT_TRUE(without.status.ok()) << without.status.error_message();
  EXPECT_FALSE(without.summary->has_table());
  EXPECT_EQ(without.summary->objects_size(), 0);
  for (const v1::LabelChunk& chunk : without.chunks) EXPECT_TRUE(chunk.objects().empty());
}

}  // namespace
}  // namespace primlabel::servertest
