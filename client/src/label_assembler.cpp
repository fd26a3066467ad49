#include "label_assembler.hpp"

#include <limits>
#include <string>

#include "primlabel/wire/packing.hpp"

namespace primlabel::client {

namespace {
constexpr std::uint32_t kNoSegment = 0xFFFFFFFFu;  // LabelChunk.segments: in no segment
constexpr std::uint32_t kNoObject = 0xFFFFFFFFu;   // LabelChunk.objects: neither table nor object
std::string at(std::uint64_t first) { return "chunk at point " + std::to_string(first); }
}  // namespace

LabelAssembler::LabelAssembler(std::size_t points, bool want_descriptors, bool want_probabilities,
                               bool want_segments, bool want_objects)
    : points_(points),
      want_descriptors_(want_descriptors),
      want_probabilities_(want_probabilities),
      want_segments_(want_segments),
      want_objects_(want_objects),
      covered_(points, 0) {
  result_.labels.assign(points, 0);
}

int LabelAssembler::columns(std::size_t bytes, std::uint32_t count, const char* what,
                            std::uint64_t first) {
  if (bytes == 0) return -1;
  if (count == 0 || bytes % (4ull * count) != 0)
    throw ProtocolError(at(first) + ": " + std::to_string(bytes) + " bytes of " + what +
                        " do not divide into " + std::to_string(count) + " points");
  return static_cast<int>(bytes / (4ull * count));
}

void LabelAssembler::add_ids(const std::string& bytes, std::uint32_t count, std::uint64_t first,
                             bool wanted, const char* what, std::vector<std::uint32_t>& out) {
  const int id_columns = columns(bytes.size(), count, what, first);
  if (wanted && count > 0 && id_columns < 0)
    throw ProtocolError(at(first) + ": " + what + " were asked for but are missing");
  if (id_columns > 1)
    throw ProtocolError(at(first) + ": " + std::to_string(id_columns) + " " + what +
                        " a point, not 1");
  if (id_columns == 1) {
    if (out.empty()) out.assign(points_, kNoSegment);
    wire::unpack_u32(bytes, out.data() + first);
  }
}

void LabelAssembler::add(const v1::LabelChunk& chunk) {
  const std::uint64_t first = chunk.first_point();
  const std::uint32_t count = chunk.point_count();
  if (first > points_ || count > points_ - first)
    throw ProtocolError(at(first) + ": " + std::to_string(count) + " points run past the " +
                        std::to_string(points_) + " points sent");
  if (chunk.labels().size() != wire::kLabelBytesPerPoint * count)
    throw ProtocolError(at(first) + ": " + std::to_string(chunk.labels().size()) +
                        " bytes of labels for " + std::to_string(count) + " points");
  for (std::uint64_t i = first; i < first + count; ++i)
    if (covered_[i]) throw ProtocolError(at(first) + ": point " + std::to_string(i) + " twice");

  const int dim = columns(chunk.descriptors().size(), count, "descriptors", first);
  if (want_descriptors_ && count > 0 && dim < 0)
    throw ProtocolError(at(first) + ": descriptors were asked for but are missing");
  if (dim > 0) {
    if (result_.descriptor_dim == 0) {
      result_.descriptor_dim = dim;
      result_.descriptors.assign(points_ * dim, std::numeric_limits<float>::quiet_NaN());
    } else if (dim != result_.descriptor_dim) {
      throw ProtocolError(at(first) + ": " + std::to_string(dim) + " descriptor values a point, " +
                          "earlier chunks had " + std::to_string(result_.descriptor_dim));
    }
    wire::unpack_f32(chunk.descriptors(), result_.descriptors.data() + first * dim);
  }

  const int classes = columns(chunk.probabilities().size(), count, "probabilities", first);
  if (want_probabilities_ && count > 0 && classes < 0)
    throw ProtocolError(at(first) + ": probabilities were asked for but are missing");
  if (classes > 0) {
    if (probability_columns_ < 0) {
      probability_columns_ = classes;
      result_.probabilities.assign(points_ * classes, 0.0f);
    } else if (classes != probability_columns_) {
      throw ProtocolError(at(first) + ": " + std::to_string(classes) +
                          " probabilities a point, earlier chunks had " +
                          std::to_string(probability_columns_));
    }
    wire::unpack_f32(chunk.probabilities(), result_.probabilities.data() + first * classes);
  }

  add_ids(chunk.segments(), count, first, want_segments_, "segment ids", result_.segments);
  add_ids(chunk.objects(), count, first, want_objects_, "object ids", result_.object_ids);

  wire::unpack_u32(chunk.labels(), result_.labels.data() + first);
  for (std::uint64_t i = first; i < first + count; ++i) covered_[i] = 1;
  covered_count_ += count;
}

LabelResult LabelAssembler::finish(const v1::LabelSummary& summary) {
  if (covered_count_ != points_) {
    std::size_t missing = 0;
    while (missing < points_ && covered_[missing]) ++missing;
    throw ProtocolError("the answer covers " + std::to_string(covered_count_) + " of " +
                        std::to_string(points_) + " points; first missing point " +
                        std::to_string(missing));
  }
  if (summary.points_received() != points_)
    throw ProtocolError("the server received " + std::to_string(summary.points_received()) +
                        " points of " + std::to_string(points_) + " sent");
  if (result_.descriptor_dim > 0 && summary.descriptor_dim() != 0 &&
      static_cast<int>(summary.descriptor_dim()) != result_.descriptor_dim)
    throw ProtocolError("the summary says " + std::to_string(summary.descriptor_dim()) +
                        " descriptor values a point, the chunks carried " +
                        std::to_string(result_.descriptor_dim));
  if (probability_columns_ > 0) {
    if (summary.classes_size() != probability_columns_)
      throw ProtocolError("the summary lists " + std::to_string(summary.classes_size()) +
                          " classes, the chunks carried " + std::to_string(probability_columns_) +
                          " probabilities a point");
  }
  // Every segment id names one of the summary's primitives.
  const auto primitive_count = std::uint32_t(summary.primitives_size());
  for (std::size_t i = 0; i < result_.segments.size(); ++i)
    if (result_.segments[i] != kNoSegment && result_.segments[i] >= primitive_count)
      throw ProtocolError("point " + std::to_string(i) + " is in segment " +
                          std::to_string(result_.segments[i]) + ", the summary has " +
                          std::to_string(primitive_count) + " primitives");
  // Every object id names the table or one of the summary's objects.
  const auto object_count = std::uint32_t(summary.objects_size());
  for (std::size_t i = 0; i < result_.object_ids.size(); ++i) {
    const std::uint32_t id = result_.object_ids[i];
    if (id != kNoObject && (id > object_count || (id == 0 && !summary.has_table())))
      throw ProtocolError("point " + std::to_string(i) + " is in object " + std::to_string(id) +
                          ", the summary has " + std::to_string(object_count) + " objects" +
                          (summary.has_table() ? "" : " and no table"));
  }
  for (const auto& c : summary.classes()) {
    result_.class_ids.push_back(c.id());
    result_.class_names.push_back(c.name());
  }
  result_.summary = summary;
  return std::move(result_);
}

}  // namespace primlabel::client
