#include "primlabel/ros_common/labeled_pointcloud2.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include "common/class_fields.hpp"
#include "primlabel/ros_common/byte_order.hpp"
#include "primlabel/ros_common/pointcloud2_xyz.hpp"

namespace primlabel::roscommon {

namespace {

bool is_replaced(const std::string& name) {
  return name == "label" || name == "object" || name == "segment" || name == "confidence" ||
         name.rfind("prob_", 0) == 0;
}

PointFieldInfo field(const std::string& name, std::uint32_t offset, std::uint8_t datatype) {
  PointFieldInfo f;
  f.name = name;
  f.offset = offset;
  f.datatype = datatype;
  f.count = 1;
  return f;
}

// Writes the 4 bytes of `value` at `at`, in the cloud's byte order.
template <class T>
void write_word(std::uint8_t* at, T value, bool swap) {
  static_assert(sizeof(T) == 4);
  std::uint8_t bytes[4];
  std::memcpy(bytes, &value, 4);
  if (swap) std::reverse(bytes, bytes + 4);
  std::memcpy(at, bytes, 4);
}

// The highest of a point's probabilities; NaN for a point without any (no descriptor).
float highest(const float* probabilities, std::size_t classes) {
  float best = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t k = 0; k < classes; ++k)
    if (!std::isnan(probabilities[k]) && !(probabilities[k] <= best)) best = probabilities[k];
  return best;
}

}  // namespace

std::string probability_field_name(const std::string& class_name, std::uint32_t class_id) {
  return client::tools::probability_field_name(class_name, class_id);
}

PointCloud2Data labeled_pointcloud2(const PointCloud2View& input, const client::LabelResult& result,
                                    const LabeledFields& fields) {
  xyz_layout(input, input.data_size);  // the sizes the copy below relies on
  const std::size_t points = std::size_t(input.width) * input.height;
  if (result.labels.size() != points)
    throw std::invalid_argument("the service labeled " + std::to_string(result.labels.size()) +
                                " points of a cloud of " + std::to_string(points));
  const std::size_t classes = result.class_ids.size();
  const bool with_probabilities = fields.confidence || fields.probabilities;
  if (with_probabilities && result.probabilities.size() != points * classes)
    throw std::invalid_argument("the service sent no probabilities for every point");
  if (fields.object && result.object_ids.size() != points)
    throw std::invalid_argument("the service sent no object id for every point");
  if (fields.segment && result.segments.size() != points)
    throw std::invalid_argument("the service sent no segment id for every point");

  PointCloud2Data out;
  out.frame_id = input.frame_id;
  out.stamp_ns = input.stamp_ns;
  if (!result.summary.frame_id().empty() || result.summary.stamp_ns() != 0) {
    out.frame_id = result.summary.frame_id();
    out.stamp_ns = result.summary.stamp_ns();
  }
  out.width = input.width;
  out.height = input.height;
  out.is_bigendian = input.is_bigendian;
  out.is_dense = input.is_dense;
  for (const PointFieldInfo& f : input.fields)
    if (!is_replaced(f.name)) out.fields.push_back(f);
  const std::uint32_t base = (input.point_step + 3u) & ~3u;
  std::uint32_t offset = base;
  out.fields.push_back(field("label", offset, datatype::kUint32));
  offset += 4;
  if (fields.object) {
    out.fields.push_back(field("object", offset, datatype::kUint32));
    offset += 4;
  }
  if (fields.segment) {
    out.fields.push_back(field("segment", offset, datatype::kUint32));
    offset += 4;
  }
  if (fields.confidence) {
    out.fields.push_back(field("confidence", offset, datatype::kFloat32));
    offset += 4;
  }
  if (fields.probabilities)
    for (std::size_t k = 0; k < classes; ++k) {
      out.fields.push_back(
          field(probability_field_name(result.class_names.at(k), result.class_ids[k]), offset,
                datatype::kFloat32));
      offset += 4;
    }
  out.point_step = offset;
  out.row_step = out.width * out.point_step;
  out.data.assign(std::size_t(out.row_step) * out.height, 0);

  // Labels are written in the cloud's own byte order, as its copied fields are.
  const bool swap = needs_swap(input.is_bigendian);
  std::size_t i = 0;
  for (std::uint32_t row = 0; row < input.height; ++row) {
    const std::uint8_t* from = input.data + std::size_t(row) * input.row_step;
    std::uint8_t* to = out.data.data() + std::size_t(row) * out.row_step;
    for (std::uint32_t column = 0; column < input.width;
         ++column, ++i, from += input.point_step, to += out.point_step) {
      std::memcpy(to, from, input.point_step);
      std::uint8_t* extra = to + base;
      write_word(extra, result.labels[i], swap);
      extra += 4;
      if (fields.object) {
        write_word(extra, result.object_ids[i], swap);
        extra += 4;
      }
      if (fields.segment) {
        write_word(extra, result.segments[i], swap);
        extra += 4;
      }
      if (!with_probabilities) continue;
      const float* p = result.probabilities.data() + i * classes;
      if (fields.confidence) {
        write_word(extra, highest(p, classes), swap);
        extra += 4;
      }
      if (fields.probabilities)
        for (std::size_t k = 0; k < classes; ++k, extra += 4) write_word(extra, p[k], swap);
    }
  }
  return out;
}

}  // namespace primlabel::roscommon
