#pragma once
// One labeling request between "points received" and "labels ready": which model and options
// it gets (checked against what the model allows), and the labeling itself, which turns every
// way it can fail (stopped, bad options, out of memory, any other exception) into a
// ServiceError. No transport here.

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

namespace primlabel::server {

struct LabelPlan {
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
std::optional<ServiceError> plan_labeling(const v1::ScanHeader& header, ModelRegistry& registry,
                                          LabelPlan& plan);

// Finishes a choice the header left open, from the cloud's signature (a neighbour index over
// it); NOT_FOUND when no model fits and the server has no default. Runs inside the job.
std::optional<ServiceError> finish_model_choice(LabelPlan& plan, const PointCloud& cloud,
                                                const RunContext& context);

// Bytes per point of the answer the plan asks for (labels, descriptors, probabilities, segment
// ids, object ids and the objects' messages), known before labeling.
std::uint64_t answer_bytes_per_point(const LabelPlan& plan);

// A bound on one encoded v1::Primitive (a plane, the largest: 16 doubles and 4 scalars with their
// tags, about 300 bytes); test_server_service checks real messages against it.
inline constexpr std::uint64_t kMaxPrimitiveMessageBytes = 400;
// A bound on one encoded v1::TabletopObject without its primitive ids (an id, a count, three
// Vec3d and a double with their tags: about 110 bytes).
inline constexpr std::uint64_t kMaxObjectMessageBytes = 160;
// An estimate of the encoded v1::TabletopTable: the plane and up to 1024 hull vertices at 31 bytes
// each (the hull of the table's grid cells has far fewer).
inline constexpr std::uint64_t kMaxTableMessageBytes = 64 + 1024 * 31;
// Bytes the summary may carry on top of its fixed part, whatever the cloud size: the primitives
// (at most PrimitiveOptions::segments.max_segments of them) and the table with the objects'
// primitive ids (the objects themselves are counted per point in answer_bytes_per_point).
std::uint64_t answer_summary_bytes(const LabelPlan& plan);

// Finishes the model choice if it is open, then runs label_cloud; never throws. CANCELLED when
// context.stop was requested.
std::optional<ServiceError> run_label_job(LabelPlan& plan, PointCloud& cloud,
                                          const RunContext& context,
                                          pipeline::LabelingResult& result);

// RESOURCE_EXHAUSTED naming the limits, for a request refused for lack of a compute slot.
ServiceError server_busy(const Admission& admission);
// UNAVAILABLE, for requests arriving while the server drains.
ServiceError shutting_down();

}  // namespace primlabel::server
