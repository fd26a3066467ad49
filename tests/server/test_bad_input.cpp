// Bad input, each with a clear status and message while the server keeps serving: no header,
// two headers, unknown model or version, zero points, non-finite coordinates (dropped and
// counted, or refused), chunk lengths, point limits, malformed bytes, disconnects, deadlines,
// busy servers, and a reload racing with labeling.

#include <thread>

#include "server_test_util.hpp"

namespace primlabel::servertest {
namespace {

using testing::random_label_model;
using testing::table_with_box_cloud;

class BadInput : public ::testing::Test {
 protected:
  BadInput()
      : model_(random_label_model("m", "1")),
        server_({model_},
                [](ops::ServerConfig& c) {
                  c.max_points = 50000;
                  c.insecure_admin = true;  // the reload race below needs ReloadModels
                  c.max_receiving_streams = 3;
                }),
        cloud_(table_with_box_cloud(0.01f)) {}

  // The server still labels a good scan correctly.
  void expect_still_serving() {
    const LabelAnswer answer = label_stream(*server_.stub, scan_requests(cloud_, header_for()));
    ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
    EXPECT_EQ(answer.labels.size(), cloud_.size());
    EXPECT_EQ(health_status(server_.channel, ""), "SERVING");
  }

  static void expect_status(const grpc::Status& status, grpc::StatusCode code,
                            const std::string& says) {
    EXPECT_EQ(status.error_code(), code) << status.error_message();
    EXPECT_NE(status.error_message().find(says), std::string::npos) << status.error_message();
  }

  double metric(const std::string& name, const scrape::Labels& labels = {}) {
    return scrape::sum_samples(scrape_metrics(server_.server->metrics_port()), name, labels);
  }

  LabelModel model_;
  TestServer server_;
  PointCloud cloud_;
};

TEST_F(BadInput, NoHeader) {
  auto requests = scan_requests(cloud_, header_for());
  requests.erase(requests.begin());
  expect_status(label_stream(*server_.stub, requests).status, grpc::StatusCode::INVALID_ARGUMENT,
                "message 1 must be a ScanHeader, got a PointChunk");
  expect_status(label_stream(*server_.stub, {}).status, grpc::StatusCode::INVALID_ARGUMENT,
                "ended before a ScanHeader");
  expect_still_serving();
}

TEST_F(BadInput, HeaderTwice) {
  auto requests = scan_requests(cloud_, header_for());
  requests.insert(requests.begin() + 2, requests.front());
  expect_status(label_stream(*server_.stub, requests).status, grpc::StatusCode::INVALID_ARGUMENT,
                "message 3 is a ScanHeader");
  expect_still_serving();
}

TEST_F(BadInput, EmptyMessage) {
  auto requests = scan_requests(cloud_, header_for());
  requests.insert(requests.begin() + 1, v1::LabelRequest{});
  expect_status(label_stream(*server_.stub, requests).status, grpc::StatusCode::INVALID_ARGUMENT,
                "message 2 is an empty LabelRequest");
  expect_still_serving();
}

TEST_F(BadInput, UnknownModelOrVersion) {
  expect_status(label_stream(*server_.stub, scan_requests(cloud_, header_for("other"))).status,
                grpc::StatusCode::NOT_FOUND, "model 'other' is not loaded; loaded: m (1)");
  v1::ScanHeader header = header_for("m");
  header.set_model_version("7");
  expect_status(label_stream(*server_.stub, scan_requests(cloud_, header)).status,
                grpc::StatusCode::NOT_FOUND, "model 'm' has no version '7'");
  expect_still_serving();
}

TEST_F(BadInput, ZeroPoints) {
  expect_status(label_stream(*server_.stub, scan_requests(PointCloud{}, header_for())).status,
                grpc::StatusCode::INVALID_ARGUMENT, "the scan has no points");
  PointCloud none;
  v1::LabelCloudRequest request;
  *request.mutable_header() = header_for();
  grpc::ClientContext context;
  v1::LabelCloudResponse response;
  expect_status(server_.stub->LabelCloud(&context, request, &response),
                grpc::StatusCode::INVALID_ARGUMENT, "the scan has no points");
  expect_still_serving();
}

TEST_F(BadInput, NonFiniteCoordinatesAreDroppedAndCounted) {
  PointCloud cloud = cloud_;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.xyz[5] = Vec3f(nan, 0, 0);
  cloud.xyz[1234] = Vec3f(0, std::numeric_limits<float>::infinity(), 0);
  const LabelAnswer answer = label_stream(*server_.stub, scan_requests(cloud, header_for(), 1000));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.summary->points_dropped_non_finite(), 2u);
  EXPECT_EQ(answer.labels[5], 0u);
  EXPECT_EQ(answer.labels[1234], 0u);
  EXPECT_EQ(metric("primlabel_points_dropped_total", {{"reason", "non_finite"}}), 2.0);
}

TEST_F(BadInput, NonFiniteCoordinatesRejectedOnRequest) {
  PointCloud cloud = cloud_;
  cloud.xyz[1234] = Vec3f(0, std::numeric_limits<float>::infinity(), 0);
  v1::ScanHeader header = header_for();
  header.mutable_options()->set_non_finite(v1::NON_FINITE_REJECT);
  expect_status(label_stream(*server_.stub, scan_requests(cloud, header, 1000)).status,
                grpc::StatusCode::INVALID_ARGUMENT,
                "point 1234 (chunk 2) has a non-finite coordinate (0, inf, 0)");
  expect_still_serving();
}

TEST_F(BadInput, ChunkLengthNotAMultipleOfThePointSize) {
  auto requests = scan_requests(cloud_, header_for(), 1000);
  requests[3].mutable_chunk()->mutable_xyz()->append("\x01\x02\x03\x04\x05", 5);
  expect_status(label_stream(*server_.stub, requests).status, grpc::StatusCode::INVALID_ARGUMENT,
                "chunk 3: xyz has 12005 bytes, not a multiple of 12");

  v1::ScanHeader header = header_for();
  header.mutable_layout()->set_normals(true);
  PointCloud with_normals = cloud_;
  with_normals.normals.assign(cloud_.size(), Vec3f(0, 0, 1));
  requests = scan_requests(with_normals, header, 1000);
  requests[2].mutable_chunk()->mutable_normals()->resize(11988);
  expect_status(label_stream(*server_.stub, requests).status, grpc::StatusCode::INVALID_ARGUMENT,
                "chunk 2: normals has 11988 bytes; 1000 points need 12000");
  expect_still_serving();
}

TEST_F(BadInput, MorePointsThanTheLimit) {
  const PointCloud big = table_with_box_cloud(0.0025f);  // > 50000 points
  ASSERT_GT(big.size(), 50000u);
  expect_status(label_stream(*server_.stub, scan_requests(big, header_for(), 10000)).status,
                grpc::StatusCode::INVALID_ARGUMENT, "this server takes at most 50000");
  v1::ScanHeader header = header_for();
  header.set_expected_points(60000);
  expect_status(label_stream(*server_.stub, scan_requests(cloud_, header)).status,
                grpc::StatusCode::INVALID_ARGUMENT, "announces 60000 points");
  header.set_expected_points(cloud_.size() + 1);
  expect_status(label_stream(*server_.stub, scan_requests(cloud_, header)).status,
                grpc::StatusCode::INVALID_ARGUMENT, "but the header announced");
  expect_still_serving();
}

TEST_F(BadInput, RadiusOverrideTheModelDoesNotAllow) {
  v1::ScanHeader header = header_for();
  header.mutable_options()->set_feature_radius(0.05f);
  expect_status(label_stream(*server_.stub, scan_requests(cloud_, header)).status,
                grpc::StatusCode::INVALID_ARGUMENT, "does not allow radius overrides");
  header.mutable_options()->set_feature_radius(0);
  header.mutable_options()->set_voxel_size(-1);
  expect_status(label_stream(*server_.stub, scan_requests(cloud_, header)).status,
                grpc::StatusCode::INVALID_ARGUMENT, "voxel_size must be finite and >= 0");
  expect_still_serving();
}

// Raw bytes through a generic stub: a message that is not a LabelRequest.
TEST_F(BadInput, MalformedProtobufBytes) {
  grpc::GenericStub generic(server_.channel);
  for (const char* method : {"/primlabel.v1.Labeler/Label", "/primlabel.v1.Labeler/LabelCloud"}) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    grpc::CompletionQueue queue;
    auto call = generic.PrepareCall(&context, method, &queue);
    void* tag;
    bool ok;
    call->StartCall(reinterpret_cast<void*>(1));
    ASSERT_TRUE(queue.Next(&tag, &ok) && ok);
    const std::string garbage("\x0a\xff\xff\xff\xff\x0f garbage", 14);  // length past the end
    grpc::Slice slice(garbage);
    grpc::ByteBuffer bytes(&slice, 1);
    call->Write(bytes, reinterpret_cast<void*>(2));
    queue.Next(&tag, &ok);
    call->WritesDone(reinterpret_cast<void*>(3));
    queue.Next(&tag, &ok);
    grpc::Status status;
    call->Finish(&status, reinterpret_cast<void*>(4));
    while (queue.Next(&tag, &ok) && tag != reinterpret_cast<void*>(4)) {
    }
    expect_status(status, grpc::StatusCode::INVALID_ARGUMENT, "not a valid Label");
    queue.Shutdown();
    while (queue.Next(&tag, &ok)) {
    }
  }
  expect_still_serving();
}

TEST_F(BadInput, ClientDisconnectsMidStream) {
  {
    grpc::ClientContext context;
    auto stream = server_.stub->Label(&context);
    const auto requests = scan_requests(cloud_, header_for(), 1000, false);
    for (std::size_t i = 0; i < 3; ++i) ASSERT_TRUE(stream->Write(requests[i]));
    context.TryCancel();
    EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  }
  // The server notices, frees the request's place and counts it.
  for (int i = 0; i < 200 && metric("primlabel_requests_total",
                                    {{"method", "Label"}, {"status", "CANCELLED"}}) < 1;
       ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  EXPECT_EQ(metric("primlabel_requests_total", {{"method", "Label"}, {"status", "CANCELLED"}}),
            1.0);
  // The gauge drops in the reactor's OnDone, which may come after the counter: within a bound.
  for (int i = 0; i < 200 && metric("primlabel_inflight_requests") != 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  EXPECT_EQ(metric("primlabel_inflight_requests"), 0.0);
  expect_still_serving();
}

TEST_F(BadInput, DeadlineExceededWhileLabeling) {
  const PointCloud big = table_with_box_cloud(0.004f);  // ~33k points: seconds of work
  const LabelAnswer answer =
      label_stream(*server_.stub, scan_requests(big, header_for()), std::chrono::milliseconds(150));
  EXPECT_EQ(answer.status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  expect_still_serving();
}

TEST_F(BadInput, BusyServerAnswersResourceExhaustedAtHeaderTime) {
  // The receiving budget is 3 streams: hold three streams open after their headers.
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientReaderWriter<v1::LabelRequest, v1::LabelResponse>>>
      streams;
  v1::LabelRequest header;
  *header.mutable_header() = header_for();
  for (int i = 0; i < 3; ++i) {
    contexts.push_back(std::make_unique<grpc::ClientContext>());
    streams.push_back(server_.stub->Label(contexts.back().get()));
    ASSERT_TRUE(streams.back()->Write(header));
  }
  for (int i = 0; i < 200 && metric("primlabel_inflight_requests") < 3; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  ASSERT_EQ(metric("primlabel_inflight_requests"), 3.0);
  expect_status(label_stream(*server_.stub, scan_requests(cloud_, header_for())).status,
                grpc::StatusCode::RESOURCE_EXHAUSTED, "the server is busy");
  for (std::size_t i = 0; i < streams.size(); ++i) {
    contexts[i]->TryCancel();
    streams[i]->Finish();
  }
  for (int i = 0; i < 200 && metric("primlabel_inflight_requests") > 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  expect_still_serving();
}

TEST_F(BadInput, ReloadDuringLabelingNeverShowsAHalfLoadedModel) {
  // Requests run while version 1 is rewritten again and again with other weights and reloaded:
  // every answer must be exactly the labels of the version its summary names.
  const LabelModel other = random_label_model("m", "1", 99);
  const auto expected_model = reference_labels(model_, cloud_);
  const auto expected_other = reference_labels(other, cloud_);
  ASSERT_NE(expected_model, expected_other);
  std::atomic<bool> done{false};
  std::thread reloader([&] {
    for (int i = 0; !done && i < 200; ++i) {
      write_model(server_.repo.path(), i % 2 ? model_ : other);
      grpc::ClientContext context;
      v1::ReloadModelsResponse response;
      const grpc::Status status = server_.admin->ReloadModels(&context, {}, &response);
      EXPECT_TRUE(status.ok()) << status.error_message();
    }
  });
  int matched = 0;
  for (int i = 0; i < 6; ++i) {
    const LabelAnswer answer = label_stream(*server_.stub, scan_requests(cloud_, header_for()));
    ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
    matched += answer.labels == expected_model || answer.labels == expected_other;
  }
  done = true;
  reloader.join();
  EXPECT_EQ(matched, 6);
  EXPECT_EQ(metric("primlabel_model_reload_failures_total"), 0.0);
}

}  // namespace
}  // namespace primlabel::servertest
