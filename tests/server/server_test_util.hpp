#pragma once
// Fixtures of the server suites: a model repository in a temporary directory, an in-process
// server on 127.0.0.1:0, packing clouds into Label requests, and reading the answers.

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "grpc/health/v1/health.grpc.pb.h"
#include "model_repository_util.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/rpc/label_server.hpp"
#include "primlabel/scrape/exposition_parser.hpp"
#include "primlabel/scrape/http_fetch.hpp"
#include "primlabel/service/label_options.hpp"
#include "primlabel/v1/labeling.grpc.pb.h"
#include "primlabel/wire/packing.hpp"
#include "random_label_model.hpp"

namespace primlabel::servertest {

namespace fs = std::filesystem;

// The samples of http://127.0.0.1:<metrics_port>/metrics.
inline std::vector<scrape::Sample> scrape_metrics(int metrics_port) {
  return scrape::parse_exposition(
      scrape::fetch_text("http://127.0.0.1:" + std::to_string(metrics_port) + "/metrics"));
}

inline std::shared_ptr<grpc::Channel> channel_to(int port) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(64 << 20);
  return grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(port),
                                   grpc::InsecureChannelCredentials(), args);
}

// The requests of one scan: header, chunks of `per_chunk` points, end.
inline std::vector<v1::LabelRequest> scan_requests(const PointCloud& cloud,
                                                   const v1::ScanHeader& header,
                                                   std::size_t per_chunk = 20000,
                                                   bool with_end = true) {
  std::vector<v1::LabelRequest> requests(1);
  *requests[0].mutable_header() = header;
  for (std::size_t first = 0; first < cloud.size(); first += per_chunk) {
    const std::size_t count = std::min(per_chunk, cloud.size() - first);
    v1::LabelRequest request;
    v1::PointChunk& chunk = *request.mutable_chunk();
    wire::append_le(*chunk.mutable_xyz(),
                    std::span<const float>(cloud.xyz[first].data(), 3 * count));
    if (header.layout().normals())
      wire::append_le(*chunk.mutable_normals(),
                      std::span<const float>(cloud.normals[first].data(), 3 * count));
    requests.push_back(std::move(request));
  }
  if (with_end) requests.emplace_back().mutable_end();
  return requests;
}

inline v1::ScanHeader header_for(const std::string& model = "", const std::string& scan_id = "s1") {
  v1::ScanHeader header;
  header.set_model(model);
  header.set_scan_id(scan_id);
  header.mutable_viewpoint()->set_z(2.0f);
  return header;
}

struct LabelAnswer {
  grpc::Status status;
  std::vector<v1::LabelChunk> chunks;
  std::optional<v1::LabelSummary> summary;
  std::vector<std::uint32_t> labels;
  std::vector<float> descriptors, probabilities;
};

inline void unpack_chunks(LabelAnswer& answer) {
  for (const v1::LabelChunk& chunk : answer.chunks) {
    EXPECT_EQ(chunk.first_point(), answer.labels.size());
    std::size_t n = answer.labels.size();
    answer.labels.resize(n + chunk.labels().size() / 4);
    wire::unpack_le<std::uint32_t>(chunk.labels(), answer.labels.data() + n);
    n = answer.descriptors.size();
    answer.descriptors.resize(n + chunk.descriptors().size() / 4);
    wire::unpack_le<float>(chunk.descriptors(), answer.descriptors.data() + n);
    n = answer.probabilities.size();
    answer.probabilities.resize(n + chunk.probabilities().size() / 4);
    wire::unpack_le<float>(chunk.probabilities(), answer.probabilities.data() + n);
  }
}

// Sends every request (stops early if the server closes), half-closes, reads every answer.
inline LabelAnswer label_stream(v1::Labeler::Stub& stub,
                                const std::vector<v1::LabelRequest>& requests,
                                std::chrono::milliseconds deadline = std::chrono::seconds(120),
                                const std::string& token = "") {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + deadline);
  if (!token.empty()) context.AddMetadata("authorization", "Bearer " + token);
  auto stream = stub.Label(&context);
  for (const v1::LabelRequest& request : requests)
    if (!stream->Write(request)) break;
  stream->WritesDone();
  LabelAnswer answer;
  v1::LabelResponse response;
  while (stream->Read(&response)) {
    if (response.has_chunk()) answer.chunks.push_back(response.chunk());
    if (response.has_summary()) answer.summary = response.summary();
  }
  answer.status = stream->Finish();
  unpack_chunks(answer);
  return answer;
}

inline LabelAnswer label_cloud(v1::Labeler::Stub& stub, const PointCloud& cloud,
                               const v1::ScanHeader& header) {
  v1::LabelCloudRequest request;
  *request.mutable_header() = header;
  wire::append_le(*request.mutable_points()->mutable_xyz(),
                  std::span<const float>(cloud.xyz[0].data(), 3 * cloud.size()));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
  v1::LabelCloudResponse response;
  LabelAnswer answer;
  answer.status = stub.LabelCloud(&context, request, &response);
  if (answer.status.ok()) {
    answer.chunks.push_back(response.result());
    answer.summary = response.summary();
    unpack_chunks(answer);
  }
  return answer;
}

// "SERVING", "NOT_SERVING", ... or the RPC's error code as "error:N".
inline std::string health_status(const std::shared_ptr<grpc::Channel>& channel,
                                 const std::string& service) {
  auto stub = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = stub->Check(&context, request, &response);
  if (!status.ok()) return "error:" + std::to_string(status.error_code());
  return grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status());
}

// An in-process server over a fresh repository holding `models`.
struct TestServer {
  explicit TestServer(const std::vector<LabelModel>& models,
                      const std::function<void(ops::ServerConfig&)>& adjust = {})
      : repo("repo") {
    for (const LabelModel& model : models) write_model(repo.path(), model);
    ops::ServerConfig config = test_config(repo.path());
    if (adjust) adjust(config);
    server = std::make_unique<rpc::LabelServer>(config);
    channel = channel_to(server->port());
    stub = v1::Labeler::NewStub(channel);
    admin = v1::ModelAdmin::NewStub(channel);
  }
  TempDir repo;
  std::unique_ptr<rpc::LabelServer> server;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::Labeler::Stub> stub;
  std::unique_ptr<v1::ModelAdmin::Stub> admin;
};

// The reference: label_cloud in process with the same model and the options the server takes
// from a header that asks for nothing (service/label_options.hpp: the plane cascade on).
inline std::vector<std::uint32_t> reference_labels(const LabelModel& model, PointCloud cloud) {
  return pipeline::label_cloud(model, cloud, service::labeling_options(v1::ScanHeader{})).labels;
}

}  // namespace primlabel::servertest
