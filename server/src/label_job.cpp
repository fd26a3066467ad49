#include "label_job.hpp"

#include <chrono>
#include <new>
#include <stop_token>

#include "logging.hpp"
#include "registry_status.hpp"

namespace primlabel::server {

namespace {

constexpr auto kPollInterval = std::chrono::milliseconds(5);

// Why the call must stop now, if it must.
grpc::Status stop_reason(grpc::ServerContext& context) {
  const bool past_deadline = std::chrono::system_clock::now() > context.deadline();
  if (past_deadline)
    return {grpc::StatusCode::DEADLINE_EXCEEDED, "the deadline passed while labeling"};
  if (context.IsCancelled())
    return {grpc::StatusCode::CANCELLED, "the call was cancelled while labeling"};
  return grpc::Status::OK;
}

}  // namespace

grpc::Status plan_labeling(const v1::ScanHeader& header, const ServiceEnvironment& env,
                           LabelPlan& plan) {
  try {
    plan.entry = env.registry->resolve(header.model(), header.model_version());
  } catch (const RegistryError& error) {
    return registry_status(error);
  }
  const LabelModel& model = *plan.entry->model;
  const std::string which =
      "model '" + plan.entry->name + "' version '" + plan.entry->version + "'";
  const v1::LabelOptions& options = header.options();
  if ((options.normal_radius() > 0.0f || options.feature_radius() > 0.0f) &&
      !model.features.radii_overridable)
    return {grpc::StatusCode::INVALID_ARGUMENT,
            which + " does not allow radius overrides (options.normal_radius / feature_radius)"};
  plan.options.want_descriptors = options.return_descriptors();
  plan.options.want_probabilities = options.return_probabilities();
  plan.options.tabletop_only = options.tabletop_only();
  plan.options.voxel_size = options.voxel_size();
  plan.options.normal_radius = options.normal_radius();
  plan.options.feature_radius = options.feature_radius();
  plan.options.use_cloud_normals = header.layout().normals();
  return grpc::Status::OK;
}

grpc::Status run_labeling(grpc::ServerContext& context, const ServiceEnvironment& env,
                          const Admission::Ticket& ticket, const LabelPlan& plan, PointCloud& cloud,
                          pipeline::LabelingResult& result, RequestRecord& record) {
  std::stop_source stop;
  pipeline::LabelingOptions options = plan.options;
  options.stop = stop.get_token();
  options.threads = env.threads_per_job;
  grpc::Status outcome;  // written by the worker, read after it finished
  std::shared_ptr<Admission::Job> job = env.admission->submit(ticket, [&] {
    try {
      result = pipeline::label_cloud(*plan.entry->model, cloud, options);
    } catch (const pipeline::Cancelled&) {
      outcome = {grpc::StatusCode::CANCELLED, "labeling was cancelled"};
    } catch (const std::invalid_argument& e) {
      outcome = {grpc::StatusCode::INVALID_ARGUMENT, e.what()};
    } catch (const std::bad_alloc&) {
      outcome = {grpc::StatusCode::RESOURCE_EXHAUSTED, "out of memory while labeling"};
    } catch (const std::exception& e) {
      outcome = {grpc::StatusCode::INTERNAL, std::string("labeling failed: ") + e.what()};
    }
  });
  grpc::Status stopped;
  std::chrono::steady_clock::time_point stop_time;
  while (!job->wait_for(kPollInterval)) {
    if (stop.stop_requested()) continue;
    stopped = stop_reason(context);
    if (stopped.ok()) continue;
    stop_time = std::chrono::steady_clock::now();
    stop.request_stop();
    if (env.admission->abandon(job)) break;  // never started
  }
  if (!stopped.ok()) {
    log_info("labeling_stopped")
        .kv("request_id", record.id())
        .kv("reason", stopped.error_message())
        .kv("stop_ms",
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - stop_time)
                .count());
    return stopped;
  }
  if (!outcome.ok()) return outcome;
  record.stages.prefilter = result.prefilter_seconds;
  record.stages.normals = result.normal_seconds;
  record.stages.features = result.descriptor_seconds;
  record.stages.inference = result.inference_seconds;
  return grpc::Status::OK;
}

grpc::Status server_busy(const Admission& admission) {
  return {grpc::StatusCode::RESOURCE_EXHAUSTED,
          "the server is busy: " + std::to_string(admission.admitted()) +
              " requests in progress (" + std::to_string(admission.workers()) + " workers, " +
              std::to_string(admission.capacity() - admission.workers()) +
              " queued at most); retry later"};
}

grpc::Status shutting_down() {
  return {grpc::StatusCode::UNAVAILABLE, "the server is shutting down"};
}

}  // namespace primlabel::server
