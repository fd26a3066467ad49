#include "primlabel/ros_common/summary_json.hpp"

#include <google/protobuf/util/json_util.h>

#include <stdexcept>

namespace primlabel::roscommon {

std::string summary_json(const v1::LabelSummary& summary) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  std::string json;
  const auto status = google::protobuf::util::MessageToJsonString(summary, &json, options);
  if (!status.ok()) throw std::runtime_error("the summary as JSON: " + status.ToString());
  return json;
}

}  // namespace primlabel::roscommon
