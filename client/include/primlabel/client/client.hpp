#pragma once
// The C++ client of the primlabel labeling service (proto/primlabel/v1/labeling.proto).
//
//   primlabel::client::Client client({.address = "127.0.0.1:50051"});
//   primlabel::client::LabelResult r = client.label(cloud, {.model = "tabletop-lms400"});
//   // r.labels[i] is the taxonomy class of cloud.xyz[i]
//
// Every call has a deadline (ClientOptions::deadline unless the call gives one). Calls that fail
// with UNAVAILABLE are retried with exponential backoff and jitter, up to retry_attempts in all,
// within the same deadline; labeling is a pure function of the request, so a retry is safe.
// Failures throw ClientError carrying the gRPC status.

#include <grpcpp/support/status.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "primlabel/client/backoff.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::client {

struct TlsOptions {
  std::string ca_file;               // PEM roots to verify the server; empty = the system's roots
  std::string cert_file;             // PEM client certificate chain, for mutual TLS (with key_file)
  std::string key_file;              // PEM client private key
  std::string server_name_override;  // expected name in the server certificate (tests)
};

struct ClientOptions {
  std::string address = "127.0.0.1:50051";
  std::chrono::milliseconds deadline{60'000};  // per call, including its retries
  int retry_attempts = 4;                      // attempts in all on UNAVAILABLE (1 = no retry)
  BackoffPolicy backoff;
  std::optional<TlsOptions> tls;  // nothing = plaintext (loopback, or inside a trusted network)
  std::string bearer_token;       // sent as "authorization: Bearer <token>" when not empty
  // Keepalive as the server expects it: a ping every 30 s, also between calls, so a dead peer
  // behind a NAT or a restarted server is noticed before the next scan.
  std::chrono::milliseconds keepalive_time{30'000};
  std::chrono::milliseconds keepalive_timeout{10'000};
  bool keepalive_permit_without_calls = true;
  // How soon a lost connection is retried; gRPC's own default grows to two minutes, too slow for
  // a robot waiting for a restarted server.
  std::chrono::milliseconds max_reconnect_backoff{2'000};
  int max_receive_message_bytes = 64 << 20;
};

// What to ask of one labeling call.
struct LabelOptions {
  std::string model;          // empty = the server's default model
  std::string model_version;  // empty = the latest loaded version
  std::string scan_id;        // the caller's id, echoed in the summary and the server's logs
  bool descriptors = false;   // return the FPFH descriptors
  bool probabilities = false;
  bool primitives = false;  // fitted primitive instances (summary.primitives) and segment ids
  bool tabletop_only = false;
  // With tabletop_only: the table and its objects as instances (LabelResult::objects(), table())
  // and every point's object id (LabelResult::object_ids).
  bool objects = false;
  float voxel_size = 0;  // > 0: downsample before features
  // Describe and infer every point: no plane cascade (summary.cascaded_points() stays 0), the
  // model's exact labels everywhere, slower.
  bool every_point = false;
  float normal_radius = 0;
  float feature_radius = 0;
  bool reject_non_finite = false;  // NaN/Inf points fail the call instead of being labeled 0
  bool send_normals = false;       // send the cloud's normals (the server then skips estimation)
  std::optional<Vec3f> viewpoint;  // default: the cloud's viewpoint origin
  // The cloud's unit in metres: 0.001 when its coordinates are millimetres, 0.01 centimetres.
  // Points and viewpoint are scaled on the way out (the cloud itself is untouched); what comes
  // back in coordinates (primitives, objects) is in metres. Must be finite and > 0.
  float metres_per_unit = 1.0f;
  std::size_t chunk_points = 65'536;                  // points per streamed request message
  std::uint32_t response_chunk_points = 0;            // 0 = the server's default
  std::optional<std::chrono::milliseconds> deadline;  // default: ClientOptions::deadline

  // Where and when the scan was taken (e.g. a ROS header's frame_id and stamp), echoed in the
  // summary (LabelResult::frame_id(), stamp_ns()).
  std::string frame_id;
  std::uint64_t stamp_ns = 0;  // nanoseconds since the epoch; 0 = none
};

// Where one call's time went on the client, in seconds (of the attempt that answered): building
// the request messages from the cloud, handing them to gRPC (serialising and sending them),
// waiting for and reading the answer (the server's work is in here), and decoding the answer
// into LabelResult. A unary call sends and receives in one step, counted as `receive`.
struct ClientSeconds {
  double encode = 0;
  double send = 0;
  double receive = 0;
  double decode = 0;
};

// The labels of one cloud, in the order of its points.
struct LabelResult {
  std::vector<std::uint32_t> labels;     // taxonomy class id per point, 0 = unknown
  int descriptor_dim = 0;                // columns of descriptors (0 when not asked for)
  std::vector<float> descriptors;        // point-major, NaN rows for points without one
  std::vector<std::uint32_t> class_ids;  // columns of probabilities
  std::vector<std::string> class_names;
  std::vector<float> probabilities;  // point-major
  // With LabelOptions::primitives: each point's index into primitives(), 0xFFFFFFFF for none.
  std::vector<std::uint32_t> segments;
  // With LabelOptions::objects: each point's table-top object, 0 the table, k objects()[k - 1],
  // 0xFFFFFFFF neither.
  std::vector<std::uint32_t> object_ids;
  v1::LabelSummary summary;
  int attempts = 1;  // calls made, including retries
  ClientSeconds client_seconds;

  std::size_t size() const { return labels.size(); }
  // LabelOptions::frame_id and stamp_ns as the server echoed them.
  const std::string& frame_id() const { return summary.frame_id(); }
  std::uint64_t stamp_ns() const { return summary.stamp_ns(); }
  // The fitted instances (with LabelOptions::primitives), primitives()[s] for segment id s.
  const google::protobuf::RepeatedPtrField<v1::Primitive>& primitives() const {
    return summary.primitives();
  }
  // The table-top objects (with LabelOptions::objects), objects()[k - 1] for object id k, and the
  // table they stand on (has_table() false when none was found: summary.no_table_reason()).
  const google::protobuf::RepeatedPtrField<v1::TabletopObject>& objects() const {
    return summary.objects();
  }
  bool has_table() const { return summary.has_table(); }
  const v1::TabletopTable& table() const { return summary.table(); }
};

// A failed call: the gRPC status of the last attempt (or DATA_LOSS when the server's answer did
// not cover every point exactly once), and how many attempts were made.
class ClientError : public std::runtime_error {
 public:
  ClientError(grpc::StatusCode code, const std::string& message, int attempts = 1);
  grpc::StatusCode code() const { return code_; }
  int attempts() const { return attempts_; }

 private:
  grpc::StatusCode code_;
  int attempts_;
};

// "UNAVAILABLE", "DEADLINE_EXCEEDED", ...
std::string status_code_name(grpc::StatusCode code);
// How the server chose the model: "named", "domain", "default" ("" when the server did not say).
std::string model_choice_name(v1::ModelChoice choice);
// The same for people: "named by the request", "chosen by domain: <reason>", "the default:
// <reason>".
std::string model_choice_text(const v1::LabelSummary& summary);

// How a call ended, for callbacks and counters.
struct CallStatus {
  grpc::StatusCode code = grpc::StatusCode::OK;
  std::string message;
  int attempts = 1;
  bool ok() const { return code == grpc::StatusCode::OK; }
};

// The overall or one service's state as grpc.health.v1 reports it.
enum class HealthStatus { kUnknown = 0, kServing = 1, kNotServing = 2, kServiceUnknown = 3 };
std::string health_status_name(HealthStatus status);

// Cancels an asynchronous call; harmless after it finished.
class CallHandle {
 public:
  CallHandle() = default;
  void cancel();
  bool done() const;
  void wait() const;  // until the callback has returned

 private:
  friend class Client;
  struct State;
  std::shared_ptr<State> state_;
};

class Client {
 public:
  explicit Client(ClientOptions options);
  ~Client();  // cancels and waits for asynchronous calls still running
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  const ClientOptions& options() const { return options_; }

  // Streams `cloud` in chunks (Labeler.Label) and returns the labels in input order. Throws
  // ClientError. `on_progress(sent, total)` is called after each chunk is written.
  LabelResult label(const PointCloud& cloud, const LabelOptions& options = {},
                    const std::function<void(std::size_t, std::size_t)>& on_progress = {});

  // The same in one message (Labeler.LabelCloud), for small clouds.
  LabelResult label_unary(const PointCloud& cloud, const LabelOptions& options = {});

  // label() on a worker thread; `done` runs there with the outcome (result empty on failure).
  using LabelCallback = std::function<void(CallStatus, LabelResult)>;
  CallHandle label_async(PointCloud cloud, LabelOptions options, LabelCallback done,
                         bool unary = false);

  std::vector<v1::ModelInfo> list_models();
  v1::ModelMetadata model_metadata(const std::string& model, const std::string& version = "");

  // grpc.health.v1 Check for `service` ("" = the server as a whole). Throws ClientError when the
  // server cannot be reached (UNAVAILABLE) or the call fails otherwise.
  HealthStatus health(const std::string& service = "");

  struct Impl;  // the channel, stubs and worker bookkeeping (client.cpp)

 private:
  ClientOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace primlabel::client
