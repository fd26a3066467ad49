#pragma once
// The answer as a robot wants it: the input PointCloud2 with its layout kept (every field at its
// offset, width and height, is_dense, byte order) plus the labels and, optionally, the
// confidence and per-class probabilities appended to each point.

#include <cstdint>
#include <string>

#include "primlabel/client/client.hpp"
#include "primlabel/ros_common/pointcloud2.hpp"

namespace primlabel::roscommon {

struct LabeledFields {
  bool confidence = false;     // float32 `confidence`: the highest class probability (or NaN)
  bool probabilities = false;  // float32 `prob_<class>` per class, in the summary's class order
  bool object = false;         // uint32 `object`: the table-top object id (LabelResult::object_ids)
  bool segment = false;        // uint32 `segment`: the primitive segment id (LabelResult::segments)
};

// The field name of a class's probability: "prob_" + the class name with every character other
// than [A-Za-z0-9_] as '_' ("prob_<id>" for a class without a name).
std::string probability_field_name(const std::string& class_name, std::uint32_t class_id);

// `input` with a uint32 `label` (and the asked-for fields: `object`, `segment`, `confidence`,
// `prob_<class>`, in that order) appended after its own bytes, at the next 4-byte boundary; rows
// are packed (row_step = width * point_step). Input fields of the same names (e.g. a
// ground-truth `label`) are dropped from the field list, their bytes left as padding. The frame
// and stamp are the ones the service echoed (the input's when it echoed neither: a server older
// than the echo). The ids and probabilities come from `result` (LabelOptions::objects,
// primitives, probabilities) and must be there when `fields` asks for them. Throws
// std::invalid_argument when `result` does not cover the cloud's points or the input's layout
// cannot be read.
PointCloud2Data labeled_pointcloud2(const PointCloud2View& input, const client::LabelResult& result,
                                    const LabeledFields& fields);

}  // namespace primlabel::roscommon
