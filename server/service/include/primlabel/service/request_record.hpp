#pragma once
// One RPC's id, what it labeled and how long each stage took; on finish() it writes the
// request's log line and its metrics.

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

#include "primlabel/ops/server_metrics.hpp"
#include "primlabel/ops/stage_times.hpp"

namespace primlabel::service {

class RequestRecord {
 public:
  RequestRecord(std::string method, ops::ServerMetrics& metrics);
  RequestRecord(const RequestRecord&) = delete;
  RequestRecord& operator=(const RequestRecord&) = delete;

  const std::string& id() const { return id_; }
  double elapsed_seconds() const;

  // As the client sent them until the model is resolved; capped (user_text) where they are
  // logged or counted.
  std::string scan_id, model, version;
  // The scan's frame and stamp, echoed in the summary.
  std::string frame_id;
  std::uint64_t stamp_ns = 0;
  // Set once `model` names a loaded model: only then is it a metric label, so clients that send
  // made-up names cannot grow the metrics without bound (they count as model="").
  bool model_resolved = false;
  // How the model was chosen ("named", "domain", "default"); empty until it is.
  std::string model_choice;
  std::uint64_t points = 0, dropped_non_finite = 0;
  // Of the described points, those the plane cascade labeled plane (LabelSummary.cascaded_points).
  std::uint64_t cascaded = 0;
  ops::StageTimes stages;

  // Logs and counts the request once, with its outcome: the status code's name ("OK",
  // "INVALID_ARGUMENT", ...) and, when it failed, the message. The RPC edge calls it
  // (finish_request in grpc_status.hpp).
  void finish(std::string_view code, std::string_view message);

 private:
  std::string method_;
  ops::ServerMetrics& metrics_;
  std::string id_;
  std::chrono::steady_clock::time_point start_;
  bool finished_ = false;
};

// A process-unique id: a random per-process prefix and a counter, e.g. "5f3a9c01-000042".
std::string next_request_id();

}  // namespace primlabel::service
