#pragma once
// The LabelSummary as the nodes publish it (std_msgs/String): protobuf's canonical JSON with
// the .proto field names, every field present, e.g. {"request_id": "...", "frame_id": "camera",
// "stamp_ns": "1700000000123456789", "class_counts": [...], ...} (64-bit integers are strings in
// that mapping). No message package to generate, and any ROS tool or language reads it.

#include <string>

#include "primlabel/v1/labeling.pb.h"

namespace primlabel::roscommon {

std::string summary_json(const v1::LabelSummary& summary);

}  // namespace primlabel::roscommon
