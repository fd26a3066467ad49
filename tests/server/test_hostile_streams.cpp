// Hostile clients against a real server on 127.0.0.1 (the callback reactors): streams that send
// a header and then nothing, slow drips, clients that never read their answers, hundreds of open
// streams, deadlines (the client's and the server's own) and a LabelCloud answer too large for
// one message. Each is finished with a status naming the limit and the flag, frees its slots
// and memory, and legitimate clients keep being served.

#include <sys/resource.h>

#include <fstream>
#include <thread>

#include "proc_status.hpp"
#include "server_test_util.hpp"

namespace primlabel::servertest {
namespace {

using testing::random_label_model;
using testing::table_with_box_cloud;
using RawStream = grpc::ClientReaderWriter<v1::LabelRequest, v1::LabelResponse>;

long process_status(const std::string& field) { return testing::proc_status(field); }

double metric(TestServer& server, const std::string& name, const scrape::Labels& labels = {}) {
  return scrape::sum_samples(scrape_metrics(server.server->metrics_port()), name, labels);
}

// Waits (at most 20 s) until `done` holds; false if it never did.
template <typename Condition>
bool eventually(Condition done) {
  for (int i = 0; i < 800; ++i) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  return done();
}

void expect_status(const grpc::Status& status, grpc::StatusCode code, const std::string& says) {
  EXPECT_EQ(status.error_code(), code) << status.error_message();
  EXPECT_NE(status.error_message().find(says), std::string::npos) << status.error_message();
}

// An open stream that has sent its header (and whatever else the test writes).
struct OpenStream {
  explicit OpenStream(v1::Labeler::Stub& stub,
                      std::chrono::seconds deadline = std::chrono::seconds(60)) {
    context.set_deadline(std::chrono::system_clock::now() + deadline);
    stream = stub.Label(&context);
    v1::LabelRequest header;
    *header.mutable_header() = header_for();
    stream->Write(header);
  }
  grpc::Status cancel_and_finish() {
    context.TryCancel();
    return stream->Finish();
  }
  grpc::ClientContext context;
  std::unique_ptr<RawStream> stream;
};

TEST(HostileStreams, IdleStreamsBeyondTheBudgetDoNotStopALegitimateRequest) {
  const LabelModel model = random_label_model("m", "1");
  TestServer server({model}, [](ops::ServerConfig& c) {
    c.max_receiving_streams = 4;
    c.stream_idle_seconds = 0.5;
  });
  const PointCloud cloud = table_with_box_cloud(0.01f);
  const auto requests = scan_requests(cloud, header_for(), 500);

  // The legitimate client streams its scan at a steady pace while the idle streams arrive.
  std::atomic<bool> admitted{false};
  LabelAnswer legitimate;
  std::thread client([&] {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    auto stream = server.stub->Label(&context);
    for (std::size_t i = 0; i < requests.size(); ++i) {
      if (!stream->Write(requests[i])) break;
      if (i == 1) admitted = true;
      std::this_thread::sleep_for(std::chrono::milliseconds(40));
    }
    stream->WritesDone();
    v1::LabelResponse response;
    while (stream->Read(&response)) {
      if (response.has_chunk()) legitimate.chunks.push_back(response.chunk());
      if (response.has_summary()) legitimate.summary = response.summary();
    }
    legitimate.status = stream->Finish();
    unpack_chunks(legitimate);
  });
  ASSERT_TRUE(eventually([&] { return admitted.load(); }));

  // 3 places are left: 3 idle streams get them, 5 more are refused at their header.
  std::vector<std::unique_ptr<OpenStream>> idle;
  for (int i = 0; i < 8; ++i) idle.push_back(std::make_unique<OpenStream>(*server.stub));
  int refused = 0, timed_out = 0;
  for (auto& stream : idle) {
    const grpc::Status status = stream->stream->Finish();  // the server ends every one
    if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) {
      ++refused;
      EXPECT_NE(status.error_message().find("--max-receiving-streams"), std::string::npos)
          << status.error_message();
    } else {
      ++timed_out;
      expect_status(status, grpc::StatusCode::DEADLINE_EXCEEDED, "(--stream-idle-seconds)");
    }
  }
  EXPECT_EQ(refused, 5);
  EXPECT_EQ(timed_out, 3);
  client.join();
  ASSERT_TRUE(legitimate.status.ok()) << legitimate.status.error_message();
  EXPECT_EQ(legitimate.labels, reference_labels(model, cloud));
  // Every place is free again.
  EXPECT_TRUE(eventually([&] { return metric(server, "primlabel_inflight_requests") == 0; }));
  EXPECT_TRUE(label_stream(*server.stub, scan_requests(cloud, header_for())).status.ok());
}

TEST(HostileStreams, SlowDripBelowTheMinimumRateIsCut) {
  const LabelModel model = random_label_model("m", "1");
  TestServer server({model}, [](ops::ServerConfig& c) {
    c.min_receive_bytes_per_second = 50000;
    c.receive_rate_window_seconds = 0.25;
  });
  const PointCloud cloud = table_with_box_cloud(0.01f);
  // 10 points (120 bytes) every 50 ms: never idle, but ~2.4 kB/s.
  const auto drip = scan_requests(cloud, header_for(), 10, false);
  OpenStream stream(*server.stub);
  for (std::size_t i = 1; i < drip.size() && i < 200; ++i) {
    if (!stream.stream->Write(drip[i])) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  expect_status(stream.stream->Finish(), grpc::StatusCode::RESOURCE_EXHAUSTED,
                "(--min-receive-bytes-per-second)");
  EXPECT_TRUE(eventually([&] { return metric(server, "primlabel_inflight_requests") == 0; }));
  // A client at full speed is not affected by the minimum.
  const LabelAnswer answer = label_stream(*server.stub, scan_requests(cloud, header_for(), 500));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.labels, reference_labels(model, cloud));
}

TEST(HostileStreams, ClientsThatNeverReadAreCancelledAndTheirMemoryFreed) {
  const LabelModel model = random_label_model("m", "1");
  TestServer server({model}, [](ops::ServerConfig& c) {
    c.send_timeout_seconds = 0.5;
    c.workers = 1;
    c.queue = 8;
  });
  // ~165k points, labeled through 5 cm voxels (little work), answered with descriptors and
  // probabilities for every point: ~26 MB of answer per request.
  const PointCloud cloud = table_with_box_cloud(0.0015f);
  v1::ScanHeader header = header_for();
  header.mutable_options()->set_voxel_size(0.05f);
  header.mutable_options()->set_return_descriptors(true);
  header.mutable_options()->set_return_probabilities(true);
  const auto requests = scan_requests(cloud, header, 50000);
  const double answer_mb = double(cloud.size()) * (4 + 33 * 4 + 5 * 4) / 1e6;
  ASSERT_GT(answer_mb, 20.0);

  const long threads_before = process_status("Threads");
  const long hwm_before_kb = process_status("VmHWM");
  constexpr int kWaves = 4, kPerWave = 3;
  for (int wave = 0; wave < kWaves; ++wave) {
    std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
    std::vector<std::unique_ptr<RawStream>> streams;
    for (int i = 0; i < kPerWave; ++i) {
      contexts.push_back(std::make_unique<grpc::ClientContext>());
      streams.push_back(server.stub->Label(contexts.back().get()));
      for (const auto& request : requests) ASSERT_TRUE(streams.back()->Write(request));
      streams.back()->WritesDone();  // and never Read
    }
    // The server gives up on each within the send timeout and frees it.
    const double expected = double((wave + 1) * kPerWave);
    ASSERT_TRUE(eventually([&] {
      return metric(server, "primlabel_requests_total",
                    {{"method", "Label"}, {"status", "DEADLINE_EXCEEDED"}}) == expected;
    })) << "wave "
        << wave;
    EXPECT_TRUE(eventually([&] { return metric(server, "primlabel_inflight_requests") == 0; }));
    EXPECT_LE(process_status("Threads"), threads_before + 16);
    for (std::size_t i = 0; i < streams.size(); ++i) {
      contexts[i]->TryCancel();
      streams[i]->Finish();
    }
  }
  // Held answers would add up over the waves (kWaves * kPerWave * answer_mb, ~300 MB); freed,
  // the peak is about one wave's (answers, their encoded chunks, the clients' buffers).
  const double growth_mb = double(process_status("VmHWM") - hwm_before_kb) / 1e3;
  std::printf("VmHWM growth %.0f MB over %d waves of %d clients (answer %.0f MB each)\n", growth_mb,
              kWaves, kPerWave, answer_mb);
  EXPECT_LT(growth_mb, 2.0 * kPerWave * answer_mb + 100.0);
  EXPECT_TRUE(label_stream(*server.stub, scan_requests(table_with_box_cloud(0.01f), header_for()))
                  .status.ok());
}

TEST(HostileStreams, FiveHundredIdleStreamsDoNotTakeFiveHundredThreads) {
  TestServer server({random_label_model("m", "1")}, [](ops::ServerConfig& c) {
    c.max_receiving_streams = 600;
    c.stream_idle_seconds = 60;
  });
  const long threads_before = process_status("Threads");
  std::vector<std::unique_ptr<OpenStream>> streams;
  for (int i = 0; i < 500; ++i) streams.push_back(std::make_unique<OpenStream>(*server.stub));
  ASSERT_TRUE(eventually([&] { return metric(server, "primlabel_inflight_requests") == 500; }));
  const long threads_open = process_status("Threads");
  std::printf("threads: %ld before, %ld with 500 open streams\n", threads_before, threads_open);
  EXPECT_LT(threads_open, threads_before + 50);
  for (auto& stream : streams) stream->cancel_and_finish();
  EXPECT_TRUE(eventually([&] { return metric(server, "primlabel_inflight_requests") == 0; }));
  EXPECT_TRUE(label_stream(*server.stub, scan_requests(table_with_box_cloud(0.01f), header_for()))
                  .status.ok());
}

TEST(HostileStreams, DeadlinesAreCountedAsDeadlineExceeded) {
  TestServer server({random_label_model("m", "1")},
                    [](ops::ServerConfig& c) { c.max_request_seconds = 0.3; });
  // ~130k points: about a second of work on an idle machine, several under load, so both
  // deadlines below (150 ms, 0.3 s) always expire first.
  const PointCloud big = table_with_box_cloud(0.002f);
  // The client's deadline.
  const LabelAnswer answer =
      label_stream(*server.stub, scan_requests(big, header_for()), std::chrono::milliseconds(150));
  EXPECT_EQ(answer.status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  // No deadline from the client: the server's --max-request-seconds.
  grpc::ClientContext context;  // no deadline
  auto stream = server.stub->Label(&context);
  for (const auto& request : scan_requests(big, header_for())) stream->Write(request);
  stream->WritesDone();
  v1::LabelResponse response;
  while (stream->Read(&response)) {
  }
  expect_status(stream->Finish(), grpc::StatusCode::DEADLINE_EXCEEDED, "--max-request-seconds");
  EXPECT_TRUE(eventually([&] {
    return metric(server, "primlabel_requests_total",
                  {{"method", "Label"}, {"status", "DEADLINE_EXCEEDED"}}) >= 2;
  }));
  EXPECT_EQ(metric(server, "primlabel_requests_total", {{"status", "CANCELLED"}}), 0.0);
  EXPECT_TRUE(eventually([&] { return metric(server, "primlabel_inflight_requests") == 0; }));
}

TEST(HostileStreams, LabelCloudOverTheMessageLimitIsRefusedBeforeLabeling) {
  TestServer server({random_label_model("m", "1")},
                    [](ops::ServerConfig& c) { c.max_message_bytes = 1 << 20; });
  const PointCloud cloud = table_with_box_cloud(0.004f);  // ~33k points: 400 kB in, 4.5 MB out
  v1::ScanHeader header = header_for();
  header.mutable_options()->set_return_descriptors(true);
  const LabelAnswer answer = label_cloud(*server.stub, cloud, header);
  expect_status(answer.status, grpc::StatusCode::RESOURCE_EXHAUSTED,
                "over the server's message limit of 1048576 (--max-message-bytes); use the "
                "streaming Label RPC");
  // Nothing was computed: no labeling stage ran.
  EXPECT_EQ(metric(server, "primlabel_stage_seconds_count", {{"stage", "features"}}), 0.0);
  EXPECT_EQ(metric(server, "primlabel_stage_seconds_count", {{"stage", "normals"}}), 0.0);
  // Without descriptors the answer fits.
  header.mutable_options()->set_return_descriptors(false);
  EXPECT_TRUE(label_cloud(*server.stub, table_with_box_cloud(0.01f), header).status.ok());
}

}  // namespace
}  // namespace primlabel::servertest
