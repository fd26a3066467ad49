// The fitted object truth of an mOSD scene, written as a labeled cloud for inspection.

#include <filesystem>

#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/research/mosd_report.hpp"

namespace primlabel::research {

std::size_t MosdObjectTruth::count(FittedKind kind) const {
  std::size_t n = 0;
  for (const FittedObject& o : objects) n += o.kind == kind;
  return n;
}

MosdObjectTruth fit_mosd_truth(const PointCloud& cloud, const MosdTruthRequest& request,
                               const RunContext& context, std::vector<std::uint32_t>* labels) {
  if (!cloud.has_labels())
    throw std::runtime_error("no label field (an mOSD scene labels table and objects)");
  const std::vector<int> segments = mosd_segments(cloud.labels);
  const ObjectTruth truth = fit_object_truth(cloud, segments, request.options, context);
  MosdObjectTruth out;
  out.objects = truth.objects;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (segments[i] <= 0 || !is_finite(cloud.xyz[i])) continue;
    ++out.object_points;
    out.truth_points += truth.labels[i] != class_id(PrimitiveClass::kUnknown);
  }
  if (!request.write_path.empty()) {
    PointCloud labeled;
    labeled.xyz = cloud.xyz;
    labeled.rgba = cloud.rgba;
    labeled.width = cloud.width;
    labeled.height = cloud.height;
    labeled.viewpoint = cloud.viewpoint;
    labeled.labels = truth.labels;
    FloatField& segment = labeled.set_field("segment", 1);
    for (std::size_t i = 0; i < cloud.size(); ++i) segment.values[i] = float(segments[i]);
    write_tagged_cloud(request.write_path, labeled,
                       {{"classes", class_map_tag(ClassMap::taxonomy())},
                        {"truth", "fitted"},
                        {"label_radius", std::to_string(request.options.label_radius)}});
    out.truth_file = request.write_path;
  }
  if (labels) *labels = truth.labels;
  return out;
}

}  // namespace primlabel::research
