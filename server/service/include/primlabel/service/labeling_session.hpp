#pragma once
// The core of one labeling request, with no transport in it: the header is checked and the
// model planned, the points assembled, the job run on a worker, and the answer's size known
// before labeling. Errors are ServiceErrors; the gRPC adapters (label_stream_reactor.cpp,
// label_cloud_reactor.cpp) move bytes, keep time and map errors to statuses.
//
// Places a request holds: a receiving slot (streamed scans only) from its header to the complete
// scan, a compute slot (Admission: workers + queue) from the complete scan until its result is
// computed, and the in-flight gauge from the accepted header until the session is destroyed.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

#include "primlabel/service/answer_size.hpp"
#include "primlabel/service/job_plan.hpp"
#include "primlabel/service/request_record.hpp"
#include "primlabel/service/scan_assembler.hpp"
#include "primlabel/service/service_environment.hpp"

namespace primlabel::service {

class LabelingSession {
 public:
  LabelingSession(const ServiceEnvironment& env, RequestRecord& record);
  ~LabelingSession();  // a job still running keeps nothing of the session (see run)
  LabelingSession(const LabelingSession&) = delete;
  LabelingSession& operator=(const LabelingSession&) = delete;

  // The header: checked, the model resolved; a streamed scan also takes a receiving slot.
  std::optional<ServiceError> start(const v1::ScanHeader& header, bool streamed);
  std::optional<ServiceError> add(const v1::PointChunk& chunk);
  // The scan is complete: checked, its receiving slot given back, a compute slot taken and the
  // job queued. `done` runs once on the worker thread when the job has ended (its compute slot
  // and the points already freed), unless stop() returns true. The caller keeps the session
  // alive until then.
  std::optional<ServiceError> run(std::function<void()> done);
  // Requests the job's stop at once; true when no worker had started it (`done` never runs).
  bool stop();
  // After `done`: the job's error, or nothing and the stage times are in the record, each
  // stage up to `send` (which the caller times from job_ended()) covering the call without gaps:
  // prefilter from the complete scan (the wait for a worker included) to the description,
  // normals with the neighbour index and shared search (features when
  // the client sent normals), inference with the graph, BP and the
  // fan-out to every point.
  std::optional<ServiceError> outcome();
  std::chrono::steady_clock::time_point job_ended() const { return job_end_; }

  const v1::ScanHeader& header() const { return header_; }
  const JobPlan& plan() const { return plan_; }
  std::uint64_t points() const { return assembler_ ? assembler_->points() : 0; }
  // The answer's per-point arrays in bytes, from the point count and the options.
  std::uint64_t answer_bytes() const {
    return points() * answer_bytes_per_point(plan_) + answer_summary_bytes(plan_);
  }
  const pipeline::LabelingResult& result() const { return result_; }
  void free_result();

 private:
  void note_model();  // the plan's model into the record

  const ServiceEnvironment& env_;
  ops::RequestGauge* const requests_;  // copied: the session may outlive the environment's owner
  IdleMemoryTrimmer* const trimmer_;
  RequestRecord& record_;
  v1::ScanHeader header_;
  JobPlan plan_;
  std::optional<ScanAssembler> assembler_;
  std::optional<SlotBudget::Slot> receiving_;
  std::optional<Admission::Ticket> ticket_;  // given back by the worker when the job ends
  bool counted_ = false;
  std::chrono::steady_clock::time_point receive_start_, scan_complete_, job_start_, job_end_;
  std::stop_source stop_;
  std::shared_ptr<Admission::Job> job_;
  std::optional<ServiceError> job_error_;  // written by the worker before `done`
  pipeline::LabelingResult result_;
};

// A streamed scan with no room among the receiving streams.
ServiceError receiving_busy(const SlotBudget& budget);

}  // namespace primlabel::service
