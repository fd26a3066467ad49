// The labeling service in process on 127.0.0.1:0: streamed and unary labeling give exactly the
// labels of label_cloud in process, optional arrays and chunking, the model RPCs, health,
// reflection and metrics.

#include <grpcpp/ext/proto_server_reflection_plugin.h>

#include <algorithm>
#include <chrono>
#include <random>
#include <thread>

#include "primlabel/geometry/cloud_signature.hpp"
#include "server_test_util.hpp"
#include "small_svm_model.hpp"

namespace primlabel::servertest {
namespace {

using testing::random_label_model;
using testing::table_with_box_cloud;

// Serves `model` alone and streams it the 1 cm table scan in chunks of 1000 points, expecting
// label_cloud's labels in process; the answer is for the case's own checks.
LabelAnswer stream_table_expecting_in_process_labels(const LabelModel& model) {
  TestServer server({model});
  const PointCloud cloud = table_with_box_cloud(0.01f);
  LabelAnswer answer =
      label_stream(*server.stub, scan_requests(cloud, header_for(model.name), 1000));
  EXPECT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.labels, reference_labels(model, cloud));
  return answer;
}

TEST(LabelService, StreamedLabelsMatchLabelCloudInProcess) {
  const LabelAnswer answer =
      stream_table_expecting_in_process_labels(random_label_model("tabletop", "1"));
  const PointCloud cloud = table_with_box_cloud(0.01f);
  ASSERT_TRUE(answer.summary);
  EXPECT_EQ(answer.summary->model(), "tabletop");
  EXPECT_EQ(answer.summary->model_version(), "1");
  EXPECT_EQ(answer.summary->scan_id(), "s1");
  EXPECT_EQ(answer.summary->points_received(), cloud.size());
  EXPECT_FALSE(answer.summary->request_id().empty());
  std::uint64_t counted = 0;
  for (const auto& count : answer.summary->class_counts()) counted += count.points();
  EXPECT_EQ(counted, cloud.size());
  std::vector<std::string> stages;
  for (const auto& timing : answer.summary->timings()) stages.push_back(timing.stage());
  EXPECT_EQ(stages, (std::vector<std::string>{"receive", "prefilter", "normals", "features",
                                              "inference", "send"}));
}

// ScanHeader.frame_id and stamp_ns come back in the summary, streamed and unary, and stay empty
// when not sent (a ROS node puts its header's frame and stamp on the labeled cloud from them).
TEST(LabelService, TheSummaryEchoesFrameIdAndStamp) {
  const LabelModel model = random_label_model("tabletop", "1");
  TestServer server({model});
  const PointCloud cloud = table_with_box_cloud(0.02f);
  v1::ScanHeader header = header_for("tabletop");
  header.set_frame_id("camera_depth_optical_frame");
  header.set_stamp_ns(1'700'000'000'123'456'789ull);
  const LabelAnswer streamed = label_stream(*server.stub, scan_requests(cloud, header, 1000));
  ASSERT_TRUE(streamed.status.ok()) << streamed.status.error_message();
  EXPECT_EQ(streamed.summary->frame_id(), "camera_depth_optical_frame");
  EXPECT_EQ(streamed.summary->stamp_ns(), 1'700'000'000'123'456'789ull);
  header.set_frame_id("base_laser");
  header.set_stamp_ns(42);
  const LabelAnswer unary = label_cloud(*server.stub, cloud, header);
  ASSERT_TRUE(unary.status.ok()) << unary.status.error_message();
  EXPECT_EQ(unary.summary->frame_id(), "base_laser");
  EXPECT_EQ(unary.summary->stamp_ns(), 42u);
  const LabelAnswer plain =
      label_stream(*server.stub, scan_requests(cloud, header_for("tabletop"), 1000));
  ASSERT_TRUE(plain.status.ok()) << plain.status.error_message();
  EXPECT_EQ(plain.summary->frame_id(), "");
  EXPECT_EQ(plain.summary->stamp_ns(), 0u);
}

// The summary carries the cloud's point spacing, and a warning when the model was trained for a
// spacing far from it (here: recorded as 10x finer than the 1 cm table grid).
TEST(LabelService, TheSummaryWarnsOfACloudOutsideTheModelsSpacing) {
  LabelModel fitting = random_label_model("fitting", "1");
  fitting.training.point_spacing_min = 0.008f, fitting.training.point_spacing_max = 0.012f;
  LabelModel finer = random_label_model("finer", "1");
  finer.training.point_spacing_min = 0.0008f, finer.training.point_spacing_max = 0.0012f;
  TestServer server({fitting, finer});
  const PointCloud cloud = table_with_box_cloud(0.01f);
  const LabelAnswer fits =
      label_stream(*server.stub, scan_requests(cloud, header_for("fitting"), 1000));
  ASSERT_TRUE(fits.status.ok()) << fits.status.error_message();
  EXPECT_NEAR(fits.summary->point_spacing(), 0.01f, 0.002f);
  EXPECT_EQ(fits.summary->domain_warning(), "");
  const LabelAnswer warned =
      label_stream(*server.stub, scan_requests(cloud, header_for("finer"), 1000));
  ASSERT_TRUE(warned.status.ok()) << warned.status.error_message();
  EXPECT_EQ(warned.labels, reference_labels(finer, cloud));  // labeled all the same
  EXPECT_NE(warned.summary->domain_warning().find("sparser"), std::string::npos)
      << warned.summary->domain_warning();
}

// SVM models (the paper's baseline) are served like CRFs: the same labels as in process.
TEST(LabelService, SvmModelsLabelAsInProcess) {
  LabelModel model = testing::train_small_svm_model();
  model.name = "svm";
  model.version = "1";
  const LabelAnswer answer = stream_table_expecting_in_process_labels(model);
  ASSERT_TRUE(answer.summary);
  EXPECT_GT(answer.summary->points_labeled(), table_with_box_cloud(0.01f).size() / 2);
}

// A model that takes shape evidence (the table-top objects fitted with boxes and cylinders) labels
// through the service exactly as in process, and the evidence is what it weighs: the same weights
// without it label otherwise.
TEST(LabelService, ShapeEvidenceModelsLabelAsInProcess) {
  LabelModel model = random_label_model("shapes", "1");
  model.features.shape_evidence = true;
  model.weights = crf::CrfModel::zeros(model.class_ids(), kFpfhSize + kShapeEvidenceDim);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> uniform(-4.0f, 4.0f);
  for (Eigen::Index r = 0; r < model.weights.node_weights.rows(); ++r)
    for (Eigen::Index c = 0; c < model.weights.node_weights.cols(); ++c)
      model.weights.node_weights(r, c) = uniform(rng);
  const std::vector<std::uint32_t> in_process =
      stream_table_expecting_in_process_labels(model).labels;
  const PointCloud cloud = table_with_box_cloud(0.01f);
  LabelModel blind = model;
  blind.features.shape_evidence = false;
  blind.weights.descriptor_dim = kFpfhSize;
  const int knots = static_cast<int>(blind.weights.node_knots.size());
  const int per_value = knots ? knots : 1;
  Eigen::MatrixXf kept(model.weights.node_weights.rows(), kFpfhSize * per_value + 1);
  kept << model.weights.node_weights.leftCols(kFpfhSize * per_value),
      model.weights.node_weights.rightCols(1);
  blind.weights.node_weights = kept;
  blind.weights.edge_weights = Eigen::MatrixXf::Zero(kept.rows(), kFpfhSize + 1);
  EXPECT_NE(reference_labels(blind, cloud), in_process) << "the evidence changes labels";
}

// The plane cascade is the service's default (LabelOptions.every_point turns it off): a model
// that recorded its training scans' noise labels the planar points of a noisy table plane without
// describing them, LabelSummary.cascaded_points counts them, and the labels are label_cloud's
// with the matching option, with the cascade and without it.
// The table with its box, 0.5 mm of noise on every coordinate (a laser scanner's).
PointCloud noisy_table_with_box() {
  PointCloud cloud = table_with_box_cloud(0.005f);
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, 0.0005f);
  for (Vec3f& p : cloud.xyz) p += Vec3f(noise(rng), noise(rng), noise(rng));
  return cloud;
}

TEST(LabelService, ThePlaneCascadeIsTheDefaultAndEveryPointTurnsItOff) {
  const PointCloud cloud = noisy_table_with_box();
  LabelModel model = random_label_model("cascade", "1");
  // What primlabel-train records of its scans: here the very cloud's roughness.
  model.training.roughness_max = measure_signature(cloud.xyz, cloud.viewpoint.origin).roughness;
  ASSERT_GT(model.training.roughness_max, 0.0003f);
  TestServer server({model});
  const auto in_process = [&](bool cascade) {
    PointCloud local = cloud;
    pipeline::LabelingOptions options;
    options.plane_cascade = cascade;
    return pipeline::label_cloud(model, local, options);
  };

  const LabelAnswer cascaded =
      label_stream(*server.stub, scan_requests(cloud, header_for("cascade"), 5000));
  ASSERT_TRUE(cascaded.status.ok()) << cascaded.status.error_message();
  const pipeline::LabelingResult with = in_process(true);
  EXPECT_GT(with.cascaded_points, cloud.size() / 4);  // the table, away from the box
  EXPECT_EQ(cascaded.summary->cascaded_points(), with.cascaded_points);
  EXPECT_EQ(cascaded.labels, with.labels);
  const std::uint32_t plane = class_id(PrimitiveClass::kPlane);
  EXPECT_GE(std::size_t(std::count(cascaded.labels.begin(), cascaded.labels.end(), plane)),
            with.cascaded_points);

  v1::ScanHeader header = header_for("cascade");
  header.mutable_options()->set_every_point(true);
  const LabelAnswer every = label_cloud(*server.stub, cloud, header);  // unary alike
  ASSERT_TRUE(every.status.ok()) << every.status.error_message();
  const pipeline::LabelingResult without = in_process(false);
  EXPECT_EQ(every.summary->cascaded_points(), 0u);
  EXPECT_EQ(without.cascaded_points, 0u);
  EXPECT_EQ(every.labels, without.labels);
  // The random weights call many table points something else: the cascade really decided.
  EXPECT_NE(every.labels, cascaded.labels);

  // Descriptors asked for: every point is described, so the cascade stands aside by itself.
  header = header_for("cascade");
  header.mutable_options()->set_return_descriptors(true);
  const LabelAnswer described = label_cloud(*server.stub, cloud, header);
  ASSERT_TRUE(described.status.ok()) << described.status.error_message();
  EXPECT_EQ(described.summary->cascaded_points(), 0u);
  EXPECT_EQ(described.labels, without.labels);
}

// A model without a plane class has no label for the cascade's points: it describes them all,
// as with every_point (none is left unknown).
TEST(LabelService, AModelWithoutAPlaneClassDescribesEveryPoint) {
  const PointCloud cloud = noisy_table_with_box();
  LabelModel model = random_label_model("planeless", "1");
  model.weights = crf::CrfModel::zeros({2, 4, 5, 6}, kFpfhSize);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  model.weights.node_weights =
      model.weights.node_weights.unaryExpr([&](float) { return uniform(rng); });
  model.training.roughness_max = measure_signature(cloud.xyz, cloud.viewpoint.origin).roughness;
  TestServer server({model});
  const LabelAnswer answer = label_cloud(*server.stub, cloud, header_for("planeless"));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.summary->cascaded_points(), 0u);
  PointCloud local = cloud;
  const pipeline::LabelingResult exact = pipeline::label_cloud(model, local, {});
  EXPECT_EQ(answer.labels, exact.labels);
  EXPECT_EQ(answer.summary->points_labeled(), exact.labeled_points);
}

TEST(LabelService, DescriptorsProbabilitiesAndSmallResponseChunks) {
  const LabelModel model = random_label_model("m", "1");
  TestServer server({model});
  const PointCloud cloud = table_with_box_cloud(0.01f);
  v1::ScanHeader header = header_for();  // the only model is the default
  header.mutable_options()->set_return_descriptors(true);
  header.mutable_options()->set_return_probabilities(true);
  header.mutable_options()->set_response_chunk_points(777);
  const LabelAnswer answer = label_stream(*server.stub, scan_requests(cloud, header, 500));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.chunks.size(), (cloud.size() + 776) / 777);
  for (std::size_t c = 0; c + 1 < answer.chunks.size(); ++c)
    EXPECT_EQ(answer.chunks[c].point_count(), 777u);
  ASSERT_EQ(answer.summary->descriptor_dim(), 33u);
  EXPECT_EQ(answer.summary->descriptor_name(), model.features.descriptor_name());
  ASSERT_EQ(answer.summary->classes_size(), 5);
  ASSERT_EQ(answer.descriptors.size(), cloud.size() * 33);
  ASSERT_EQ(answer.probabilities.size(), cloud.size() * 5);

  PointCloud local = cloud;
  pipeline::LabelingOptions options;
  options.want_descriptors = options.want_probabilities = true;
  const auto expected = pipeline::label_cloud(model, local, options);
  EXPECT_EQ(answer.labels, expected.labels);
  for (std::size_t i = 0; i < answer.descriptors.size(); i += 101) {
    const float a = answer.descriptors[i], b = expected.descriptors.values[i];
    ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << i;
  }
  for (std::size_t i = 0; i < cloud.size(); i += 97)
    for (int k = 0; k < 5; ++k) {
      const float a = answer.probabilities[i * 5 + k], b = expected.probabilities(i, k);
      ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << i;
    }
}

TEST(LabelService, ClientNormalsAndHalfCloseWithoutEndOfScan) {
  const LabelModel model = random_label_model("m", "1");
  TestServer server({model});
  PointCloud cloud = table_with_box_cloud(0.01f);
  const auto expected = reference_labels(model, cloud);
  PointCloud with_normals = cloud;
  pipeline::label_cloud(model, with_normals, {});  // fills the normals the server would compute
  v1::ScanHeader header = header_for();
  header.mutable_layout()->set_normals(true);
  const LabelAnswer answer =
      label_stream(*server.stub, scan_requests(with_normals, header, 1500, /*with_end=*/false));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.labels, expected);
  for (const auto& timing : answer.summary->timings())
    if (timing.stage() == "normals") EXPECT_EQ(timing.seconds(), 0.0);
}

TEST(LabelService, UnaryLabelCloudAndVoxelOption) {
  const LabelModel model = random_label_model("m", "1");
  TestServer server({model});
  const PointCloud cloud = table_with_box_cloud(0.005f);
  LabelAnswer answer = label_cloud(*server.stub, cloud, header_for("m"));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.labels, reference_labels(model, cloud));

  v1::ScanHeader header = header_for("m");
  header.mutable_options()->set_voxel_size(0.01f);
  answer = label_cloud(*server.stub, cloud, header);
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  PointCloud local = cloud;
  pipeline::LabelingOptions options;
  options.voxel_size = 0.01f;
  EXPECT_EQ(answer.labels, pipeline::label_cloud(model, local, options).labels);
}

// A model's own voxel size (a depth-camera model trained on voxels) is applied by the server
// when the request names none, and the request's replaces it.
TEST(LabelService, TheModelsVoxelSizeIsAppliedUnlessTheRequestNamesOne) {
  LabelModel model = random_label_model("voxels", "1");
  model.features.voxel_size = 0.01f;
  TestServer server({model});
  const PointCloud cloud = table_with_box_cloud(0.005f);
  PointCloud local = cloud;
  const pipeline::LabelingResult expected = pipeline::label_cloud(model, local);
  ASSERT_LT(expected.described_points, cloud.size() / 2);  // the voxels, not every point
  LabelAnswer answer = label_cloud(*server.stub, cloud, header_for("voxels"));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.labels, expected.labels);
  EXPECT_EQ(answer.labels.size(), cloud.size());  // every point gets its voxel's label

  v1::ScanHeader header = header_for("voxels");
  header.mutable_options()->set_voxel_size(0.02f);
  answer = label_cloud(*server.stub, cloud, header);
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  local = cloud;
  pipeline::LabelingOptions coarser;
  coarser.voxel_size = 0.02f;
  const std::vector<std::uint32_t> coarse = pipeline::label_cloud(model, local, coarser).labels;
  EXPECT_EQ(answer.labels, coarse);
  EXPECT_NE(coarse, expected.labels);
}

TEST(LabelService, LatestOrPinnedVersionAndExplicitVersions) {
  const LabelModel v2 = random_label_model("m", "2", 11);
  const LabelModel v10 = random_label_model("m", "10", 12);
  const PointCloud cloud = table_with_box_cloud(0.01f);
  {
    TestServer server({v2, v10});
    LabelAnswer answer = label_cloud(*server.stub, cloud, header_for("m"));
    ASSERT_TRUE(answer.status.ok());
    EXPECT_EQ(answer.summary->model_version(), "10");  // "10" is later than "2"
    EXPECT_EQ(answer.labels, reference_labels(v10, cloud));
    v1::ScanHeader header = header_for("m");
    header.set_model_version("2");
    answer = label_cloud(*server.stub, cloud, header);
    ASSERT_TRUE(answer.status.ok());
    EXPECT_EQ(answer.summary->model_version(), "2");
    EXPECT_EQ(answer.labels, reference_labels(v2, cloud));
  }
  TestServer pinned({v2, v10}, [](ops::ServerConfig& c) { c.pins["m"] = "2"; });
  const LabelAnswer answer = label_cloud(*pinned.stub, cloud, header_for("m"));
  ASSERT_TRUE(answer.status.ok());
  EXPECT_EQ(answer.summary->model_version(), "2");
}

TEST(LabelService, ListModelsAndMetadata) {
  LabelModel a = random_label_model("alpha", "1");
  a.validation.accuracy = 0.75;
  const LabelModel b = random_label_model("beta", "3");
  TestServer server({a, b}, [](ops::ServerConfig& c) { c.default_model = "beta"; });
  grpc::ClientContext context;
  v1::ListModelsResponse list;
  ASSERT_TRUE(server.stub->ListModels(&context, {}, &list).ok());
  ASSERT_EQ(list.models_size(), 2);
  EXPECT_EQ(list.models(0).name(), "alpha");
  EXPECT_FALSE(list.models(0).is_default());
  EXPECT_DOUBLE_EQ(list.models(0).validation_accuracy(), 0.75);
  EXPECT_EQ(list.models(1).name(), "beta");
  EXPECT_EQ(list.models(1).version(), "3");
  EXPECT_TRUE(list.models(1).is_default());
  EXPECT_EQ(list.models(1).classes(), 5u);
  EXPECT_EQ(list.models(1).kind(), v1::MODEL_KIND_NODE_ONLY);

  grpc::ClientContext meta_context;
  v1::GetModelMetadataRequest request;
  request.set_model("alpha");
  v1::ModelMetadata metadata;
  ASSERT_TRUE(server.stub->GetModelMetadata(&meta_context, request, &metadata).ok());
  EXPECT_EQ(metadata.name(), "alpha");
  EXPECT_EQ(metadata.version(), "1");
  EXPECT_EQ(metadata.classes_size(), 5);
  EXPECT_EQ(metadata.path(), "alpha/1/model.plm");
  EXPECT_NE(metadata.model_crc32(), 0u);
  EXPECT_FLOAT_EQ(metadata.features().feature_radius(), 0.03f);
  EXPECT_EQ(metadata.created_by(), "random_label_model");

  grpc::ClientContext missing_context;
  request.set_model("gamma");
  const grpc::Status missing = server.stub->GetModelMetadata(&missing_context, request, &metadata);
  EXPECT_EQ(missing.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(missing.error_message().find("gamma"), std::string::npos);
}

TEST(LabelService, HealthFollowsLoadedModels) {
  TestServer empty({});
  EXPECT_EQ(health_status(empty.channel, ""), "NOT_SERVING");
  EXPECT_EQ(health_status(empty.channel, "primlabel.v1.Labeler"), "NOT_SERVING");
  const LabelAnswer answer = label_cloud(*empty.stub, table_with_box_cloud(0.02f), header_for());
  EXPECT_EQ(answer.status.error_code(), grpc::StatusCode::NOT_FOUND);

  TestServer server({random_label_model()});
  EXPECT_EQ(health_status(server.channel, ""), "SERVING");
  EXPECT_EQ(health_status(server.channel, "primlabel.v1.Labeler"), "SERVING");
}

TEST(LabelService, ReflectionListsTheServices) {
  TestServer server({random_label_model()});
  // grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo with list_services = "":
  // field 7 (string), empty.
  grpc::GenericStub generic(server.channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  grpc::CompletionQueue queue;
  auto call = generic.PrepareCall(
      &context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &queue);
  void* tag;
  bool ok;
  call->StartCall(reinterpret_cast<void*>(1));
  ASSERT_TRUE(queue.Next(&tag, &ok) && ok);
  const std::string list_services("\x3a\x00", 2);
  grpc::Slice slice(list_services);
  grpc::ByteBuffer request(&slice, 1);
  call->Write(request, reinterpret_cast<void*>(2));
  ASSERT_TRUE(queue.Next(&tag, &ok) && ok);
  grpc::ByteBuffer reply;
  call->Read(&reply, reinterpret_cast<void*>(3));
  ASSERT_TRUE(queue.Next(&tag, &ok) && ok);
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(reply.Dump(&slices).ok());
  std::string bytes;
  for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  EXPECT_NE(bytes.find("primlabel.v1.Labeler"), std::string::npos);
  EXPECT_NE(bytes.find("primlabel.v1.ModelAdmin"), std::string::npos);
  EXPECT_NE(bytes.find("grpc.health.v1.Health"), std::string::npos);
  context.TryCancel();
  grpc::Status finished;
  call->Finish(&finished, reinterpret_cast<void*>(4));
  while (queue.Next(&tag, &ok)) {
    if (tag == reinterpret_cast<void*>(4)) break;
  }
  queue.Shutdown();
  while (queue.Next(&tag, &ok)) {
  }
}

TEST(LabelService, MetricsCountRequestsPointsAndStages) {
  const LabelModel model = random_label_model("m", "1");
  TestServer server({model});
  const PointCloud cloud = table_with_box_cloud(0.01f);
  ASSERT_TRUE(label_stream(*server.stub, scan_requests(cloud, header_for())).status.ok());
  EXPECT_EQ(label_cloud(*server.stub, cloud, header_for("nope")).status.error_code(),
            grpc::StatusCode::NOT_FOUND);
  using scrape::sum_samples;
  // A call's status can reach the client before the server's reactor is done with it (OnDone,
  // where the in-flight gauge drops): scrape until it has, within a bound.
  auto samples = scrape_metrics(server.server->metrics_port());
  for (int attempt = 0; attempt < 100 && sum_samples(samples, "primlabel_inflight_requests") != 0;
       ++attempt) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    samples = scrape_metrics(server.server->metrics_port());
  }
  EXPECT_EQ(sum_samples(samples, "primlabel_requests_total",
                        {{"method", "Label"}, {"model", "m"}, {"status", "OK"}}),
            1.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_requests_total",
                        {{"method", "LabelCloud"}, {"status", "NOT_FOUND"}}),
            1.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_points_total", {{"model", "m"}}), double(cloud.size()));
  for (const char* stage : {"receive", "normals", "features", "inference", "send"})
    EXPECT_EQ(sum_samples(samples, "primlabel_stage_seconds_count", {{"stage", stage}}), 1.0)
        << stage;
  EXPECT_EQ(sum_samples(samples, "primlabel_request_seconds_count", {{"method", "Label"}}), 1.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_model_info", {{"model", "m"}, {"version", "1"}}), 1.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_models_loaded"), 1.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_model_reloads_total"), 1.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_model_reload_failures_total"), 0.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_inflight_requests"), 0.0);
  EXPECT_EQ(sum_samples(samples, "primlabel_queue_depth"), 0.0);
}

}  // namespace
}  // namespace primlabel::servertest
