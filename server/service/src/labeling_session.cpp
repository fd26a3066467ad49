#include "primlabel/service/labeling_session.hpp"

#include <algorithm>

namespace primlabel::service {

namespace {

ScanLimits limits_of(const ops::ServerConfig& config) {
  return ScanLimits{config.max_points, config.max_request_bytes};
}

double seconds_between(std::chrono::steady_clock::time_point from,
                       std::chrono::steady_clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

}  // namespace

ServiceError receiving_busy(const SlotBudget& budget) {
  return {ErrorCode::kResourceExhausted,
          "the server is busy: " + std::to_string(budget.used()) +
              " streams are receiving points, the most it takes at once "
              "(--max-receiving-streams " +
              std::to_string(budget.capacity()) + "); retry later"};
}

LabelingSession::LabelingSession(const ServiceEnvironment& env, RequestRecord& record)
    : env_(env), requests_(env.requests), trimmer_(env.trimmer), record_(record) {}

void LabelingSession::free_result() {
  const std::uint64_t points = result_.labels.size();
  result_ = pipeline::LabelingResult{};
  if (trimmer_) trimmer_->released(points);
}

LabelingSession::~LabelingSession() {
  if (counted_) requests_->add_in_flight(-1);
  // A scan refused while it arrived still held its points until now.
  if (trimmer_ && assembler_) trimmer_->released(assembler_->points());
}

std::optional<ServiceError> LabelingSession::start(const v1::ScanHeader& header, bool streamed) {
  receive_start_ = std::chrono::steady_clock::now();
  header_ = header;
  record_.scan_id = header.scan_id();
  record_.frame_id = header.frame_id();
  record_.stamp_ns = header.stamp_ns();
  record_.model = header.model();
  const ScanLimits limits = limits_of(*env_.config);
  if (auto invalid = check_header(header, limits)) return invalid;
  if (auto refused = plan_job(header, *env_.registry, plan_)) return refused;
  if (plan_.entry) note_model();
  if (streamed) {
    receiving_ = env_.receiving->try_take();
    if (!receiving_) return receiving_busy(*env_.receiving);
  }
  counted_ = true;
  requests_->add_in_flight(1);
  assembler_.emplace(header, limits);
  return std::nullopt;
}

std::optional<ServiceError> LabelingSession::add(const v1::PointChunk& chunk) {
  std::optional<ServiceError> refused = assembler_->add(chunk);
  record_.points = assembler_->points();
  record_.dropped_non_finite = assembler_->non_finite();
  return refused;
}

std::optional<ServiceError> LabelingSession::run(std::function<void()> done) {
  record_.points = assembler_->points();
  record_.dropped_non_finite = assembler_->non_finite();
  if (auto incomplete = assembler_->finish()) return incomplete;
  scan_complete_ = std::chrono::steady_clock::now();
  record_.stages.receive = seconds_between(receive_start_, scan_complete_);
  receiving_.reset();
  ticket_ = env_.admission->try_admit();
  if (!ticket_) return server_busy(*env_.admission);
  const int threads = env_.threads_per_job;
  job_ = env_.admission->submit(*ticket_, [this, threads, done = std::move(done)] {
    job_start_ = std::chrono::steady_clock::now();
    job_error_ =
        run_label_job(plan_, assembler_->cloud(), RunContext{threads, stop_.get_token()}, result_);
    job_end_ = std::chrono::steady_clock::now();
    // The compute slot and the points go as soon as the result exists, not when it is sent.
    assembler_->cloud() = PointCloud{};
    ticket_.reset();
    done();
  });
  return std::nullopt;
}

bool LabelingSession::stop() {
  stop_.request_stop();
  if (!job_) return true;
  if (!env_.admission->abandon(job_)) return false;
  ticket_.reset();  // the work never runs, so nothing else touches the ticket
  return true;
}

void LabelingSession::note_model() {
  record_.model = plan_.entry->name;
  record_.model_resolved = true;
  record_.version = plan_.entry->version;
  record_.model_choice = pipeline::choice_reason_name(plan_.choice);
}

std::optional<ServiceError> LabelingSession::outcome() {
  if (plan_.entry && !record_.model_resolved) note_model();  // chosen in the job
  if (job_error_) return job_error_;
  record_.cascaded = result_.cascaded_points;
  ops::StageTimes& stages = record_.stages;
  const pipeline::StageSeconds& seconds = result_.seconds;
  // The model choice, when it measured the cloud, counts with the work before the description.
  const double prefilter = seconds.voxels + seconds.tabletop + seconds.duplicates;
  stages.prefilter = seconds_between(scan_complete_, job_start_) + plan_.choice_seconds + prefilter;
  // The neighbour index and shared search go to the first stage that searches: the normals, or
  // the features when the client sent its own normals (normals then stay 0). The plane cascade's
  // split counts with the features: it decides which points get a descriptor (0 when it stands
  // aside), so "features" stays the time from normals to descriptors, whichever points they cover.
  const double search = seconds.index + seconds.lists;
  const bool own_normals = plan_.options.use_cloud_normals;
  stages.normals = seconds.normals + (own_normals ? 0.0 : search);
  // Shape evidence is model input too: with the features.
  stages.features =
      seconds.cascade + seconds.descriptors + seconds.shapes + (own_normals ? search : 0.0);
  if (result_.primitives) stages.primitives = seconds.primitives;
  // The rest of the job: graph, inference and the fan-out (never below 0 by rounding).
  stages.inference =
      std::max(0.0, seconds_between(job_start_, job_end_) - plan_.choice_seconds - prefilter -
                        stages.normals - stages.features - seconds.primitives);
  return std::nullopt;
}

}  // namespace primlabel::service
