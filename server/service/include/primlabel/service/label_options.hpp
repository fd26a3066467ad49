#pragma once
// A request's options as the pipeline takes them: the one place the service reads
// v1::LabelOptions, and the one check of them (pipeline::validate), with its reason told in the
// request's terms.

#include <optional>

#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/service/model_registry.hpp"
#include "primlabel/service/service_error.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::service {

pipeline::LabelingOptions labeling_options(const v1::ScanHeader& header);

// INVALID_ARGUMENT when no model could honour `options`, or when `model` cannot (then naming it;
// `chosen`: the request named it, else it is one the server may still choose).
std::optional<ServiceError> refuse_options(const pipeline::LabelingOptions& options);
std::optional<ServiceError> refuse_options(const pipeline::LabelingOptions& options,
                                           const ModelEntry& model, bool chosen);

}  // namespace primlabel::service
