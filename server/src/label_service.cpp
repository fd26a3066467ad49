#include "label_service.hpp"

#include "free_memory.hpp"

namespace primlabel::server {

namespace {

ScanLimits limits_of(const ServerConfig& config) {
  return ScanLimits{config.max_points, config.max_request_bytes};
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

ServiceError receiving_busy(const SlotBudget& budget) {
  return {ErrorCode::kResourceExhausted,
          "the server is busy: " + std::to_string(budget.used()) +
              " streams are receiving points, the most it takes at once "
              "(--max-receiving-streams " +
              std::to_string(budget.capacity()) + "); retry later"};
}

LabelSession::LabelSession(const ServiceEnvironment& env, RequestRecord& record)
    : env_(env), requests_(env.requests), record_(record) {}

void LabelSession::free_result() {
  const std::uint64_t points = result_.labels.size();
  result_ = pipeline::LabelingResult{};
  return_free_memory(points);
}

LabelSession::~LabelSession() {
  if (counted_) requests_->add_in_flight(-1);
}

std::optional<ServiceError> LabelSession::start(const v1::ScanHeader& header, bool streamed) {
  receive_start_ = std::chrono::steady_clock::now();
  header_ = header;
  record_.scan_id = header.scan_id();
  record_.frame_id = header.frame_id();
  record_.stamp_ns = header.stamp_ns();
  record_.model = header.model();
  const ScanLimits limits = limits_of(*env_.config);
  if (auto invalid = check_header(header, limits)) return invalid;
  if (auto refused = plan_labeling(header, *env_.registry, plan_)) return refused;
  record_.model = plan_.entry->name;
  record_.model_resolved = true;
  record_.version = plan_.entry->version;
  if (streamed) {
    receiving_ = env_.receiving->try_take();
    if (!receiving_) return receiving_busy(*env_.receiving);
  }
  counted_ = true;
  requests_->add_in_flight(1);
  assembler_.emplace(header, limits);
  return std::nullopt;
}

std::optional<ServiceError> LabelSession::add(const v1::PointChunk& chunk) {
  std::optional<ServiceError> refused = assembler_->add(chunk);
  record_.points = assembler_->points();
  record_.dropped_non_finite = assembler_->non_finite();
  return refused;
}

std::optional<ServiceError> LabelSession::run(std::function<void()> done) {
  record_.points = assembler_->points();
  record_.dropped_non_finite = assembler_->non_finite();
  if (auto incomplete = assembler_->finish()) return incomplete;
  record_.stages.receive = seconds_since(receive_start_);
  receiving_.reset();
  ticket_ = env_.admission->try_admit();
  if (!ticket_) return server_busy(*env_.admission);
  const int threads = env_.threads_per_job;
  job_ = env_.admission->submit(*ticket_, [this, threads, done = std::move(done)] {
    job_error_ =
        run_label_job(plan_, assembler_->cloud(), RunContext{threads, stop_.get_token()}, result_);
    // The compute slot and the points go as soon as the result exists, not when it is sent.
    const std::uint64_t points = assembler_->points();
    assembler_->cloud() = PointCloud{};
    ticket_.reset();
    return_free_memory(points);
    done();
  });
  return std::nullopt;
}

bool LabelSession::stop() {
  stop_.request_stop();
  if (!job_) return true;
  if (!env_.admission->abandon(job_)) return false;
  ticket_.reset();  // the work never runs, so nothing else touches the ticket
  return true;
}

std::optional<ServiceError> LabelSession::outcome() {
  if (job_error_) return job_error_;
  record_.stages.prefilter = result_.prefilter_seconds;
  record_.stages.normals = result_.normal_seconds;
  record_.stages.features = result_.descriptor_seconds;
  record_.stages.inference = result_.inference_seconds;
  if (result_.primitives) record_.stages.primitives = result_.primitive_seconds;
  return std::nullopt;
}

}  // namespace primlabel::server
