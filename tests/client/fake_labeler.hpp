#pragma once
// An in-process stand-in for the labeling server, for client tests that need no real model:
// every point's label is round(x) (so a test chooses the labels by placing points), descriptors
// are 33 values (point index + column / 100) and probabilities 3 columns (label share 1). Faults
// can be switched on: UNAVAILABLE for the next calls, answers that skip or repeat a point, a
// required bearer token, an unknown-model rejection.

#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <prometheus/counter.h>
#include <prometheus/family.h>

#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "primlabel/client/client.hpp"
#include "primlabel/v1/labeling.grpc.pb.h"
#include "primlabel/wire/packing.hpp"

namespace primlabel::test {

class FakeLabeler final : public v1::Labeler::Service {
 public:
  static constexpr int kDescriptorDim = 33;
  static constexpr int kClasses = 3;
  static constexpr std::int64_t kCreatedUnixMs = 1767323045123;  // 2026-01-02 03:04:05.123 UTC

  std::atomic<int> unavailable_calls{0};  // fail this many next calls with UNAVAILABLE
  std::atomic<int> exhausted_calls{0};    // then this many with RESOURCE_EXHAUSTED (admission)
  std::atomic<bool> skip_a_point{false};  // answer without the last point
  std::atomic<bool> repeat_a_point{false};
  std::atomic<bool> reversed_chunks{false};  // send chunks last first (still a valid answer)
  std::atomic<int> delay_ms{0};              // before answering, e.g. to test cancellation
  std::string required_token;                // "" = none
  std::atomic<int> label_calls{0};
  std::atomic<int> chunks_received{0};
  std::atomic<std::uint64_t> points_received{0};
  std::mutex mutex;
  std::vector<std::string> scan_ids;      // in arrival order
  std::vector<v1::PointLayout> layouts;   // of each scan, in arrival order (guarded by mutex)
  std::vector<v1::LabelOptions> options;  // likewise
  std::vector<Vec3f> viewpoints;          // likewise
  std::vector<Vec3f> first_points;        // each scan's first point as received (NaN: none)

  // When set, every Label / LabelCloud call is counted here as the real server does:
  // primlabel_requests_total{method, model, status}.
  prometheus::Family<prometheus::Counter>* requests_total = nullptr;

  grpc::Status Label(
      grpc::ServerContext* context,
      grpc::ServerReaderWriter<v1::LabelResponse, v1::LabelRequest>* stream) override {
    return counted("Label", label_stream(context, stream));
  }

  grpc::Status LabelCloud(grpc::ServerContext* context, const v1::LabelCloudRequest* request,
                          v1::LabelCloudResponse* response) override {
    return counted("LabelCloud", label_unary(context, request, response));
  }

 private:
  grpc::Status counted(const std::string& method, grpc::Status status) {
    if (requests_total)
      requests_total
          ->Add({{"method", method},
                 {"model", "fake"},
                 {"status", client::status_code_name(status.error_code())}})
          .Increment();
    return status;
  }

  grpc::Status label_stream(grpc::ServerContext* context,
                            grpc::ServerReaderWriter<v1::LabelResponse, v1::LabelRequest>* stream) {
    ++label_calls;
    if (auto status = admit(context); !status.ok()) return status;
    v1::LabelRequest request;
    v1::ScanHeader header;
    std::vector<Vec3f> points;
    bool have_header = false;
    while (stream->Read(&request)) {
      if (request.has_header()) {
        if (have_header) return {grpc::StatusCode::INVALID_ARGUMENT, "header twice"};
        header = request.header();
        have_header = true;
      } else if (request.has_chunk()) {
        if (!have_header) return {grpc::StatusCode::INVALID_ARGUMENT, "chunk before header"};
        ++chunks_received;
        const auto xyz = wire::unpack_vec3<Vec3f>(request.chunk().xyz());
        points.insert(points.end(), xyz.begin(), xyz.end());
      } else {
        break;  // EndOfScan
      }
    }
    if (!have_header) return {grpc::StatusCode::INVALID_ARGUMENT, "no header"};
    std::vector<v1::LabelResponse> responses;
    v1::LabelSummary summary;
    if (auto status = answer(header, points, responses, summary); !status.ok()) return status;
    if (reversed_chunks) std::reverse(responses.begin(), responses.end());
    for (const auto& r : responses) stream->Write(r);
    v1::LabelResponse last;
    *last.mutable_summary() = summary;
    stream->Write(last);
    return grpc::Status::OK;
  }

  grpc::Status label_unary(grpc::ServerContext* context, const v1::LabelCloudRequest* request,
                           v1::LabelCloudResponse* response) {
    ++label_calls;
    if (auto status = admit(context); !status.ok()) return status;
    const auto points = wire::unpack_vec3<Vec3f>(request->points().xyz());
    v1::ScanHeader header = request->header();
    header.mutable_options()->set_response_chunk_points(0xFFFFFFFFu);  // one chunk
    std::vector<v1::LabelResponse> responses;
    if (auto status = answer(header, points, responses, *response->mutable_summary()); !status.ok())
      return status;
    if (!responses.empty()) *response->mutable_result() = responses.front().chunk();
    return grpc::Status::OK;
  }

 public:
  grpc::Status ListModels(grpc::ServerContext*, const v1::ListModelsRequest*,
                          v1::ListModelsResponse* response) override {
    auto* m = response->add_models();
    m->set_name("fake");
    m->set_version("1");
    m->add_loaded_versions("1");
    m->set_classes(kClasses);
    m->set_is_default(true);
    return grpc::Status::OK;
  }

  grpc::Status GetModelMetadata(grpc::ServerContext*, const v1::GetModelMetadataRequest* request,
                                v1::ModelMetadata* response) override {
    if (!request->model().empty() && request->model() != "fake")
      return {grpc::StatusCode::NOT_FOUND, "no model '" + request->model() + "'"};
    response->set_name("fake");
    response->set_version("1");
    response->set_created_unix_ms(kCreatedUnixMs);
    response->set_created_by("fake-trainer");
    for (int c = 0; c < kClasses; ++c) {
      auto* cls = response->add_classes();
      cls->set_id(c);
      cls->set_name("class-" + std::to_string(c));
    }
    // Class 1 had no validation points (F1 undefined); class 2 has no score entry.
    response->mutable_validation()->set_points(100);
    response->mutable_validation()->set_accuracy(0.9);
    response->mutable_validation()->add_per_class()->set_f1(0.5);
    response->mutable_validation()->add_per_class()->set_f1(std::nan(""));
    return grpc::Status::OK;
  }

 private:
  grpc::Status admit(grpc::ServerContext* context) {
    if (delay_ms > 0) {
      for (int waited = 0; waited < delay_ms && !context->IsCancelled(); waited += 5)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      if (context->IsCancelled()) return {grpc::StatusCode::CANCELLED, "cancelled"};
    }
    if (!required_token.empty()) {
      const auto& md = context->client_metadata();
      const auto it = md.find("authorization");
      if (it == md.end() ||
          std::string(it->second.data(), it->second.size()) != "Bearer " + required_token)
        return {grpc::StatusCode::UNAUTHENTICATED, "missing or wrong bearer token"};
    }
    if (take_one(unavailable_calls)) return {grpc::StatusCode::UNAVAILABLE, "fake: try again"};
    if (take_one(exhausted_calls))
      return {grpc::StatusCode::RESOURCE_EXHAUSTED, "fake: all workers busy (--queue)"};
    return grpc::Status::OK;
  }

  // Decrements `budget` when it is positive; true when it was.
  static bool take_one(std::atomic<int>& budget) {
    int expected = budget.load();
    while (expected > 0 && !budget.compare_exchange_weak(expected, expected - 1)) {
    }
    return expected > 0;
  }

  // Known instances: a plane z = 0.3 (normal +z, offset -0.3), a cylinder of radius 0.04 about
  // +z, a sphere of radius 0.05 and a line along +y, 0.5 long.
  static void fake_primitives(v1::LabelSummary& summary) {
    const auto set = [](v1::Vec3d* v, double x, double y, double z) {
      v->set_x(x), v->set_y(y), v->set_z(z);
    };
    const v1::PrimitiveKind kinds[] = {v1::PRIMITIVE_PLANE, v1::PRIMITIVE_CYLINDER,
                                       v1::PRIMITIVE_SPHERE, v1::PRIMITIVE_LINE};
    for (std::uint32_t s = 0; s < 4; ++s) {
      v1::Primitive& p = *summary.add_primitives();
      p.set_segment_id(s);
      p.set_kind(kinds[s]);
      p.set_class_id(s + 1);
      p.set_point_count(60);
      p.set_first_point(s + 1);
      p.set_inliers(50 + s);
      p.set_rms(0.001 * (s + 1));
      p.set_confidence(0.9);
      set(p.mutable_centroid(), s + 1, 1.5, 0.3);
      set(p.mutable_bounds_min(), s + 1, 0.0, 0.3);
      set(p.mutable_bounds_max(), s + 1, 3.0, 0.3);
    }
    v1::PlaneModel& plane = *summary.mutable_primitives(0)->mutable_plane();
    set(plane.mutable_normal(), 0, 0, 1);
    plane.set_offset(-0.3);
    set(plane.mutable_center(), 1, 1.5, 0.3);
    set(plane.mutable_axis_u(), 0, 1, 0);
    set(plane.mutable_axis_v(), 1, 0, 0);
    plane.set_extent_u(3.0);
    plane.set_extent_v(0.01);
    v1::CylinderModel& cylinder = *summary.mutable_primitives(1)->mutable_cylinder();
    set(cylinder.mutable_center(), 2, 1.5, 0.3);
    set(cylinder.mutable_axis(), 0, 0, 1);
    cylinder.set_radius(0.04);
    cylinder.set_height(0.12);
    v1::SphereModel& sphere = *summary.mutable_primitives(2)->mutable_sphere();
    set(sphere.mutable_center(), 3, 1.5, 0.3);
    sphere.set_radius(0.05);
    v1::LineModel& line = *summary.mutable_primitives(3)->mutable_line();
    set(line.mutable_center(), 4, 1.5, 0.3);
    set(line.mutable_direction(), 0, 1, 0);
    line.set_length(0.5);
  }

  // Known table-top objects: the table z = 0.3 (normal +z, offset -0.3) with a square hull and
  // two objects, id 1 (label 2) and id 2 (label 3), each with primitive 1 resp. 2 in it.
  static std::uint32_t fake_object_of(std::uint32_t label) {
    return label == 1 ? 0u : label == 2 ? 1u : label == 3 ? 2u : 0xFFFFFFFFu;
  }
  static void fake_objects(std::size_t table_points, v1::LabelSummary& summary) {
    const auto set = [](v1::Vec3d* v, double x, double y, double z) {
      v->set_x(x), v->set_y(y), v->set_z(z);
    };
    v1::TabletopTable& table = *summary.mutable_table();
    set(table.mutable_normal(), 0, 0, 1);
    table.set_offset(-0.3);
    for (const auto& [x, y] : {std::pair{0, 0}, {4, 0}, {4, 3}, {0, 3}})
      set(table.add_hull(), x, y, 0.3);
    table.set_point_count(table_points);
    table.add_primitive_ids(0);
    for (std::uint32_t id = 1; id <= 2; ++id) {
      v1::TabletopObject& o = *summary.add_objects();
      o.set_object_id(id);
      o.set_point_count(60);
      set(o.mutable_centroid(), id + 1, 1.5, 0.35);
      set(o.mutable_bounds_min(), id + 0.5, 0.0, 0.3);
      set(o.mutable_bounds_max(), id + 1.5, 3.0, 0.4);
      o.set_height(0.1 * id);
      o.add_primitive_ids(id);
    }
  }

  grpc::Status answer(const v1::ScanHeader& header, const std::vector<Vec3f>& points,
                      std::vector<v1::LabelResponse>& responses, v1::LabelSummary& summary) {
    if (!header.model().empty() && header.model() != "fake")
      return {grpc::StatusCode::NOT_FOUND, "no model '" + header.model() + "'"};
    if (points.empty()) return {grpc::StatusCode::INVALID_ARGUMENT, "zero points"};
    if (header.options().return_objects() && !header.options().tabletop_only())
      return {grpc::StatusCode::INVALID_ARGUMENT, "options.return_objects needs tabletop_only"};
    std::size_t table_points = 0;
    {
      std::lock_guard lock(mutex);
      scan_ids.push_back(header.scan_id());
      layouts.push_back(header.layout());
      options.push_back(header.options());
      viewpoints.emplace_back(header.viewpoint().x(), header.viewpoint().y(),
                              header.viewpoint().z());
      first_points.push_back(points.empty() ? Vec3f::Constant(std::nanf("")) : points.front());
    }
    // As the real server says how it chose: named, or (the fake's only model) the default.
    summary.set_model_choice(header.model().empty() ? v1::MODEL_CHOICE_DEFAULT
                                                    : v1::MODEL_CHOICE_NAMED);
    summary.set_model_choice_reason(header.model().empty() ? "the only model served"
                                                           : "named by the request");
    points_received += points.size();
    const std::size_t n = points.size();
    const std::size_t chunk =
        header.options().response_chunk_points() ? header.options().response_chunk_points() : 1000;
    const std::size_t answered = skip_a_point ? n - 1 : n;
    for (std::size_t first = 0; first < answered; first += chunk) {
      std::size_t count = std::min(chunk, answered - first);
      if (repeat_a_point && first + count == answered && first > 0) {
        --first;  // the last chunk starts one point early: that point is answered twice
        ++count;
      }
      v1::LabelChunk& c = *responses.emplace_back().mutable_chunk();
      c.set_first_point(first);
      c.set_point_count(static_cast<std::uint32_t>(count));
      std::vector<std::uint32_t> labels(count);
      std::vector<float> descriptors, probabilities;
      for (std::size_t i = 0; i < count; ++i) {
        labels[i] = static_cast<std::uint32_t>(std::lround(std::max(0.0f, points[first + i].x())));
        for (int d = 0; d < kDescriptorDim; ++d) descriptors.push_back((first + i) + d / 100.0f);
        for (int k = 0; k < kClasses; ++k)
          probabilities.push_back(labels[i] % kClasses == static_cast<std::uint32_t>(k));
      }
      c.set_labels(wire::pack_u32(labels.data(), count));
      if (header.options().return_descriptors())
        c.set_descriptors(wire::pack_f32(descriptors.data(), descriptors.size()));
      if (header.options().return_probabilities())
        c.set_probabilities(wire::pack_f32(probabilities.data(), probabilities.size()));
      if (header.options().return_primitives()) {
        // Label k > 0 is segment k - 1 (fake_primitives); label 0 is in none.
        std::vector<std::uint32_t> segments(count);
        for (std::size_t i = 0; i < count; ++i)
          segments[i] = labels[i] == 0 ? 0xFFFFFFFFu : labels[i] - 1;
        c.set_segments(wire::pack_u32(segments.data(), count));
      }
      if (header.options().return_objects()) {
        std::vector<std::uint32_t> objects(count);
        for (std::size_t i = 0; i < count; ++i) {
          objects[i] = fake_object_of(labels[i]);
          table_points += objects[i] == 0;
        }
        c.set_objects(wire::pack_u32(objects.data(), count));
      }
    }
    if (header.options().return_objects()) fake_objects(table_points, summary);
    if (header.options().return_primitives()) fake_primitives(summary);
    summary.set_scan_id(header.scan_id());
    summary.set_model("fake");
    summary.set_model_version("1");
    summary.set_points_received(n);
    if (header.options().return_descriptors()) {
      summary.set_descriptor_dim(kDescriptorDim);
      summary.set_descriptor_name("fpfh_paper");
    }
    for (int k = 0; k < kClasses; ++k) {
      auto* cls = summary.add_classes();
      cls->set_id(k);
      cls->set_name("class-" + std::to_string(k));
    }
    return grpc::Status::OK;
  }
};

// The fake served on 127.0.0.1 at an ephemeral port, with grpc.health.v1.
class FakeServer {
 public:
  FakeServer() {
    grpc::EnableDefaultHealthCheckService(true);
    grpc::ServerBuilder builder;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port_);
    builder.RegisterService(&service);
    server_ = builder.BuildAndStart();
  }
  ~FakeServer() { server_->Shutdown(std::chrono::system_clock::now()); }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  void set_serving(bool serving) { server_->GetHealthCheckService()->SetServingStatus(serving); }

  FakeLabeler service;

 private:
  int port_ = 0;
  std::unique_ptr<grpc::Server> server_;
};

}  // namespace primlabel::test
