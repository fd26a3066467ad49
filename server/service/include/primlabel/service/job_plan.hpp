#pragma once
// A labeling job's plan, between "header received" and "labels ready": which model and options
// the request gets (checked against what the model allows; not core's pipeline::LabelingPlan,
// which is how label_cloud works through one cloud), and running it, which turns every way it
// can fail (stopped, bad options, out of memory, any other exception) into a ServiceError. The
// answer's size: answer_size.hpp. No transport here.

#include <cstdint>
#include <memory>
#include <optional>
#include <stop_token>

#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/model_choice.hpp"
#include "primlabel/service/admission.hpp"
#include "primlabel/service/model_registry.hpp"
#include "primlabel/service/service_error.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::service {

struct JobPlan {
  // The model, held for the whole request: reloads cannot touch it. Empty until the job when
  // the request names no model and the header leaves the choice to the cloud's signature.
  std::shared_ptr<const ModelEntry> entry;
  // A request naming no model: every model served when it arrived (held, like entry: the
  // chooser reads their training summaries) and the choice in progress
  // (pipeline/model_choice.hpp); how it was decided, once it is.
  std::vector<std::shared_ptr<const ModelEntry>> candidates;
  std::shared_ptr<pipeline::ModelChooser> chooser;
  pipeline::ChoiceReason choice = pipeline::ChoiceReason::kNamed;
  std::string choice_why;
  double choice_seconds = 0;  // measuring the cloud's signature, when the choice needed it
  // A named model's shape mismatch (an organised frame sent to a model of unorganised scans),
  // prefixed to label_cloud's own domain warning.
  std::string shape_warning;
  pipeline::LabelingOptions options;  // without stop token and thread count

  // The models the answer may come from: the chosen one, or the candidates the shape left open.
  std::vector<const ModelEntry*> possible_models() const;
};

// Resolves the model (or as much of the choice as the header allows) and checks the options
// (NOT_FOUND, INVALID_ARGUMENT, FAILED_PRECONDITION).
std::optional<ServiceError> plan_job(const v1::ScanHeader& header, ModelRegistry& registry,
                                     JobPlan& plan);

// Finishes a choice the header left open, from the cloud's signature (a neighbour index over
// it); NOT_FOUND when no model fits and the server has no default. Runs inside the job.
std::optional<ServiceError> finish_model_choice(JobPlan& plan, const PointCloud& cloud,
                                                const RunContext& context);

// Finishes the model choice if it is open, then runs label_cloud; never throws. CANCELLED when
// context.stop was requested.
std::optional<ServiceError> run_label_job(JobPlan& plan, PointCloud& cloud,
                                          const RunContext& context,
                                          pipeline::LabelingResult& result);

// RESOURCE_EXHAUSTED naming the limits, for a request refused for lack of a compute slot.
ServiceError server_busy(const Admission& admission);
// UNAVAILABLE, for requests arriving while the server drains.
ServiceError shutting_down();

}  // namespace primlabel::service
