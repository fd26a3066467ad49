#include "labeled_output.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "class_fields.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/render/colorize.hpp"
#include "primlabel/render/render.hpp"

namespace primlabel::client::tools {

std::string descriptor_field(const LabelResult& result) {
  if (!result.summary.descriptor_name().empty()) return result.summary.descriptor_name();
  // A server that does not name its descriptors: only the width is known.
  return result.descriptor_dim == 125 ? "pfh" : "descriptor";
}

CloudTags labeled_cloud_tags(const LabelResult& result) {
  CloudTags tags;
  tags["model"] = result.summary.model();
  tags["model_version"] = result.summary.model_version();
  tags["model_choice"] = model_choice_name(result.summary.model_choice());
  tags["classes"] = class_map_tag(ClassMap::taxonomy());  // what the label field holds
  if (result.descriptor_dim > 0) tags["descriptor"] = descriptor_field(result);
  if (!result.probabilities.empty()) {
    std::string columns;
    // The names the server gave the columns (one word each, as the taxonomy's).
    for (std::size_t k = 0; k < result.class_ids.size() && k < result.class_names.size(); ++k) {
      if (k > 0) columns += ' ';
      columns += std::to_string(result.class_ids[k]) + ":" + result.class_names[k];
    }
    tags["probability_columns"] = columns;
  }
  if (!result.summary.scan_id().empty()) tags["scan_id"] = result.summary.scan_id();
  if (!result.summary.request_id().empty()) tags["request_id"] = result.summary.request_id();
  return tags;
}

PointCloud labeled_cloud(PointCloud cloud, const LabelResult& result) {
  if (cloud.has_labels() && cloud.labels.size() == cloud.size()) {
    FloatField& kept = cloud.set_field(kInputLabelField, 1);
    kept.values.assign(cloud.labels.begin(), cloud.labels.end());  // exact below 2^24
  }
  cloud.labels = result.labels;
  if (result.descriptor_dim > 0)
    cloud.set_field(descriptor_field(result), result.descriptor_dim).values = result.descriptors;
  // One scalar field per class, named by the class (as the ROS node names them): every reader
  // (Open3D takes a COUNT > 1 field as one column, PLY has no COUNT) sees which is which.
  if (!result.probabilities.empty() && !result.labels.empty()) {
    const std::size_t n = result.labels.size();
    const std::size_t classes = result.probabilities.size() / n;
    for (std::size_t k = 0; k < classes; ++k) {
      const std::uint32_t id = k < result.class_ids.size() ? result.class_ids[k] : std::uint32_t(k);
      const std::string name = k < result.class_names.size() ? result.class_names[k] : "";
      FloatField& field = cloud.set_field(probability_field_name(name, id), 1);
      for (std::size_t i = 0; i < n; ++i) field.values[i] = result.probabilities[i * classes + k];
    }
  }
  return cloud;
}

std::string labeled_cloud_classes_json(const PointCloud& labeled, const LabelResult& result) {
  using json::Json;
  Json out;
  out["model"] = result.summary.model();
  out["model_version"] = result.summary.model_version();
  out["model_choice"] = model_choice_name(result.summary.model_choice());
  out["label_field"] = "label";
  Json classes = Json::array();
  const ClassMap taxonomy = ClassMap::taxonomy();
  for (const ClassMap::Entry& e : taxonomy.entries())
    classes.push_back({{"id", e.id}, {"name", e.name}});
  out["classes"] = std::move(classes);
  Json probabilities = Json::array();
  for (std::size_t k = 0; k < result.class_ids.size() && k < result.class_names.size(); ++k) {
    const std::string field = probability_field_name(result.class_names[k], result.class_ids[k]);
    if (labeled.find_field(field) == nullptr) continue;
    probabilities.push_back(
        {{"field", field}, {"id", result.class_ids[k]}, {"name", result.class_names[k]}});
  }
  if (!probabilities.empty()) out["probability_fields"] = std::move(probabilities);
  if (result.descriptor_dim > 0) {
    const std::string name = descriptor_field(result);
    // PCD keeps PCL's one field of `values` floats; PLY and Open3D see one column per value.
    Json columns = Json::array();
    for (int e = 0; e < result.descriptor_dim; ++e)
      columns.push_back(name + "_" + std::to_string(e));
    out["descriptor"] = {{"field", name}, {"values", result.descriptor_dim}, {"columns", columns}};
  }
  if (labeled.find_field(kInputLabelField) != nullptr) out["input_label_field"] = kInputLabelField;
  if (labeled.find_field("object") != nullptr) out["object_field"] = "object";
  if (!result.summary.scan_id().empty()) out["scan_id"] = result.summary.scan_id();
  if (!result.summary.request_id().empty()) out["request_id"] = result.summary.request_id();
  return json::dump(out, 2) + "\n";
}

std::string classes_json_path(const std::string& cloud_path) {
  return std::filesystem::path(cloud_path).replace_extension(".classes.json").string();
}

void write_labeled_cloud(const std::string& path, const PointCloud& labeled,
                         const LabelResult& result) {
  atomic_write_file(classes_json_path(path), labeled_cloud_classes_json(labeled, result));
  // The labeled frame is on the caller's latency path: its planes are compressed in 1 MiB
  // segments on every core rather than as one stream (cloud_io.hpp: CloudWriteOptions).
  CloudWriteOptions options;
  options.lzf_segment_bytes = kLabeledCloudSegmentBytes;
  write_tagged_cloud(path, labeled, labeled_cloud_tags(result), options);
}

std::optional<RenderView> render_view(const std::string& name) {
  if (name == "auto") return std::nullopt;
  if (name == "sensor") return RenderView::kSensor;
  if (name == "top") return RenderView::kTop;
  if (name == "oblique") return RenderView::kOblique;
  throw std::invalid_argument("unknown view '" + name + "' (auto, sensor, top or oblique)");
}

void write_label_png(const PointCloud& cloud, const std::string& path,
                     const LabelPicture& picture) {
  const Coloring coloring = color_by_class(cloud, ClassMap::taxonomy());
  RenderOptions options;
  options.title = picture.title;
  options.legend = coloring.legend;
  // By default a camera frame as the camera saw it, upright.
  options.view = picture.view.value_or(natural_view(cloud));
  options.overlays = picture.overlays;
  options.crop_to_points = true;
  render_png(cloud, coloring.rgb, options, path);
}

std::string label_histogram(const PointCloud& labeled, int max) {
  const std::vector<std::uint32_t>& labels = labeled.labels;
  // Points with a position, by label: taxonomy ids are small, so counted in an array (a map
  // lookup per point cost milliseconds on a frame); any other id in the map.
  constexpr std::uint32_t kArrayIds = 256;
  std::vector<std::size_t> small_ids(kArrayIds, 0);
  std::map<std::uint32_t, std::size_t> counts;
  std::size_t no_position = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (i < labeled.xyz.size() && !is_finite(labeled.xyz[i]))
      ++no_position;
    else if (labels[i] < kArrayIds)
      ++small_ids[labels[i]];
    else
      ++counts[labels[i]];
  }
  for (std::uint32_t id = 0; id < kArrayIds; ++id)
    if (small_ids[id] > 0) counts[id] = small_ids[id];
  // The same name as the picture's legend (color_by_class).
  constexpr const char* kNoPosition = "no point (NaN)";
  std::vector<std::pair<std::size_t, std::string>> order;
  for (auto [id, n] : counts) {
    const auto cls = class_from_id(id);
    order.emplace_back(n, cls ? std::string(name(*cls)) : "label " + std::to_string(id));
  }
  if (no_position > 0) order.emplace_back(no_position, kNoPosition);
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  // Points without a position are never left out: "unknown" would hide them, silence too.
  const auto shown_at = [&](int i) {
    return i < max || (order[i].second == kNoPosition && no_position > 0);
  };
  std::string text;
  for (int i = 0; i < static_cast<int>(order.size()); ++i) {
    if (!shown_at(i)) continue;
    char share[32];
    std::snprintf(share, sizeof share, " %.0f%%", 100.0 * order[i].first / labels.size());
    text += (text.empty() ? "" : ", ") + order[i].second + share;
  }
  return text;
}

}  // namespace primlabel::client::tools
