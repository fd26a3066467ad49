#include "primlabel/service/job_plan.hpp"

#include <algorithm>
#include <chrono>
#include <new>
#include <stdexcept>

#include "primlabel/geometry/cloud_signature.hpp"
#include "primlabel/service/label_options.hpp"
#include "primlabel/service/registry_error.hpp"

namespace primlabel::service {

std::vector<const ModelEntry*> JobPlan::possible_models() const {
  if (entry) return {entry.get()};
  std::vector<const ModelEntry*> models;
  for (const auto& candidate : candidates)
    for (const pipeline::ModelCandidate& open : chooser->remaining())
      if (candidate->name == open.name) models.push_back(candidate.get());
  return models;
}

namespace {

// Takes the chooser's decision into the plan: the entry it names, or NOT_FOUND.
std::optional<ServiceError> apply_choice(JobPlan& plan) {
  const pipeline::ModelChoice& choice = plan.chooser->choice();
  if (choice.model.empty())
    return ServiceError{ErrorCode::kNotFound, "the request names no model and " + choice.why};
  for (const auto& candidate : plan.candidates)
    if (candidate->name == choice.model) plan.entry = candidate;
  if (!plan.entry)  // the chooser only names candidates; a broken invariant, not the client's
    return ServiceError{ErrorCode::kInternal, "the model chosen is not a candidate"};
  plan.choice = choice.reason;
  plan.choice_why = choice.why;
  plan.candidates.clear();
  plan.chooser.reset();
  return std::nullopt;
}

// Every served model as a candidate of the choice, in the registry's (name) order.
std::optional<ServiceError> start_choice(const pipeline::CloudShape& shape,
                                         const ModelRegistry& registry, JobPlan& plan) {
  std::vector<pipeline::ModelCandidate> candidates;
  for (const ServedModel& served : registry.list()) {
    plan.candidates.push_back(served.served);
    candidates.push_back({served.name, &served.served->model->training});
  }
  if (candidates.empty())
    return ServiceError{ErrorCode::kNotFound,
                        "the request names no model and the server has no model loaded"};
  plan.chooser =
      std::make_shared<pipeline::ModelChooser>(candidates, registry.default_model(), shape);
  if (plan.chooser->decided()) return apply_choice(plan);
  return std::nullopt;
}

}  // namespace

std::optional<ServiceError> plan_job(const v1::ScanHeader& header, ModelRegistry& registry,
                                     JobPlan& plan) {
  const pipeline::CloudShape shape{header.layout().width(), header.layout().height()};
  plan.options = labeling_options(header);
  if (auto refused = refuse_options(plan.options)) return refused;
  try {
    if (!header.model().empty() || !header.model_version().empty()) {
      // A version alone names a version of the default model, as before routing existed.
      plan.entry = registry.resolve(header.model(), header.model_version());
      plan.choice = header.model().empty() ? pipeline::ChoiceReason::kDefault
                                           : pipeline::ChoiceReason::kNamed;
      plan.choice_why =
          header.model().empty() ? "a version of the default model" : "named by the request";
      const pipeline::DomainVerdict verdict =
          pipeline::judge_shape(plan.entry->model->training, shape);
      if (verdict.fit == pipeline::DomainFit::kOutside)
        plan.shape_warning = "the cloud is an organised " + std::to_string(shape.width) + "x" +
                             std::to_string(shape.height) + " frame and this model was " +
                             verdict.why + ": labels are unreliable; use a model for this sensor";
    } else if (auto refused = start_choice(shape, registry, plan)) {
      return refused;
    }
  } catch (const RegistryError& error) {
    return registry_error(error);
  }
  for (const ModelEntry* entry : plan.possible_models())
    if (auto refused = refuse_options(plan.options, *entry, plan.entry != nullptr)) return refused;
  return std::nullopt;
}

std::optional<ServiceError> finish_model_choice(JobPlan& plan, const PointCloud& cloud,
                                                const RunContext& context) {
  if (plan.entry) return std::nullopt;
  const auto start = std::chrono::steady_clock::now();
  plan.chooser->consider(measure_signature(cloud.xyz, cloud.viewpoint.origin, context));
  plan.choice_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return apply_choice(plan);
}

std::optional<ServiceError> run_label_job(JobPlan& plan, PointCloud& cloud,
                                          const RunContext& context,
                                          pipeline::LabelingResult& result) {
  try {
    if (auto refused = finish_model_choice(plan, cloud, context)) return refused;
    result = pipeline::label_cloud(*plan.entry->model, cloud, plan.options, context);
    if (!plan.shape_warning.empty())
      result.domain_warning = result.domain_warning.empty()
                                  ? plan.shape_warning
                                  : plan.shape_warning + "; " + result.domain_warning;
    return std::nullopt;
  } catch (const pipeline::Cancelled&) {
    return ServiceError{ErrorCode::kCancelled, "labeling was cancelled"};
  } catch (const std::invalid_argument& e) {
    // The options were checked when the request came and the assembler checked the points, so
    // what label_cloud still refuses is a broken invariant of the server's, not the client's.
    return ServiceError{ErrorCode::kInternal,
                        std::string("labeling failed an internal check: ") + e.what()};
  } catch (const std::bad_alloc&) {
    return ServiceError{ErrorCode::kResourceExhausted, "out of memory while labeling"};
  } catch (const std::exception& e) {
    return ServiceError{ErrorCode::kInternal, std::string("labeling failed: ") + e.what()};
  } catch (...) {
    return ServiceError{ErrorCode::kInternal, "labeling failed: an unknown exception"};
  }
}

ServiceError server_busy(const Admission& admission) {
  return {ErrorCode::kResourceExhausted,
          "the server is busy: " + std::to_string(admission.admitted()) + " requests labeling (" +
              std::to_string(admission.workers()) + " workers, " +
              std::to_string(admission.capacity() - admission.workers()) +
              " queued at most; --workers, --queue); retry later"};
}

ServiceError shutting_down() { return {ErrorCode::kUnavailable, "the server is shutting down"}; }

}  // namespace primlabel::service
