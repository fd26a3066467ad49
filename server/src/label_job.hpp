#pragma once
// One labeling request between "points received" and "labels ready": which model and options
// it gets (checked against what the model allows), and the run on a worker thread, stopped as
// soon as the client cancels, its deadline passes or the drain deadline cancels it.

#include <grpcpp/server_context.h>
#include <grpcpp/support/status.h>

#include <memory>

#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/v1/labeling.pb.h"
#include "request_record.hpp"
#include "service_environment.hpp"

namespace primlabel::server {

struct LabelPlan {
  std::shared_ptr<const ModelEntry> entry;  // held for the whole request: reloads cannot touch it
  pipeline::LabelingOptions options;        // without stop token and thread count
};

// Resolves the model and checks the options (NOT_FOUND, INVALID_ARGUMENT, FAILED_PRECONDITION).
grpc::Status plan_labeling(const v1::ScanHeader& header, const ServiceEnvironment& env,
                           LabelPlan& plan);

// Runs label_cloud on a worker, polling the call every few milliseconds; fills the record's
// prefilter / normals / features / inference times. CANCELLED or DEADLINE_EXCEEDED when stopped.
grpc::Status run_labeling(grpc::ServerContext& context, const ServiceEnvironment& env,
                          const Admission::Ticket& ticket, const LabelPlan& plan, PointCloud& cloud,
                          pipeline::LabelingResult& result, RequestRecord& record);

// RESOURCE_EXHAUSTED naming the limits, for a request refused at admission.
grpc::Status server_busy(const Admission& admission);
// UNAVAILABLE, for requests arriving while the server drains.
grpc::Status shutting_down();

}  // namespace primlabel::server
