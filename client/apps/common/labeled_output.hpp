#pragma once
// A labeled cloud as the tools write it: the input points with `label` set to the taxonomy id,
// plus `fpfh` (or `descriptor`) and `probability` fields when the result carries them, and a PNG
// picture coloured by class.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "primlabel/client/client.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/render/render.hpp"

namespace primlabel::client::tools {

// The input cloud with the result's labels, descriptors and probabilities as float fields. A
// label field the input had (its own truth or segments) is kept as the float field
// kInputLabelField rather than lost.
inline constexpr const char* kInputLabelField = "input_label";
PointCloud labeled_cloud(PointCloud input, const LabelResult& result);

// The descriptor field's name: the server's ("fpfh" is PCL's FPFH, "fpfh_paper" the paper's
// variant, "pfh"), else "pfh" or "descriptor" by width.
std::string descriptor_field(const LabelResult& result);

// What a labeled file says about itself in its header (labeled_cloud.hpp's tags, which PCL's and
// Open3D's readers skip): model and version, the class map of `label`, the descriptor's name, the
// probability columns in order ("id:name ..."), scan and request ids.
CloudTags labeled_cloud_tags(const LabelResult& result);

// What a labeled cloud's fields hold, for readers that drop header comments (PCL, Open3D, a
// script): model, the class of every `label` value, the probability and descriptor fields and
// their columns, as JSON. Written beside the cloud as classes_json_path(cloud path).
std::string labeled_cloud_classes_json(const PointCloud& labeled, const LabelResult& result);
// "dir/scan_labeled.pcd" -> "dir/scan_labeled.classes.json".
std::string classes_json_path(const std::string& cloud_path);

// Writes the labeled cloud with its header tags, and first the classes JSON beside it, so a cloud
// that exists always has its JSON. A PCD's planes are compressed in independent LZF segments of
// kLabeledCloudSegmentBytes, in parallel (any PCD reader reads them as one stream).
inline constexpr std::size_t kLabeledCloudSegmentBytes = std::size_t(1) << 20;
void write_labeled_cloud(const std::string& path, const PointCloud& labeled,
                         const LabelResult& result);

// What a label picture shows besides the points: its title, the view (natural_view() when
// unset) and overlays such as the table-top objects (primlabel/overlays/object_overlays.hpp).
struct LabelPicture {
  std::string title;
  std::optional<RenderView> view;
  std::vector<Overlay> overlays;
};

// The view named as `--view` takes it: "sensor", "top", "oblique", or "auto" (nothing: the
// natural view). Throws std::invalid_argument for another name.
std::optional<RenderView> render_view(const std::string& name);

// Renders `cloud` coloured by its labels with the taxonomy's colours and a legend.
void write_label_png(const PointCloud& cloud, const std::string& path, const LabelPicture& picture);

// "plane 61%, no point (NaN) 38%, ..." from the labels of `labeled`, largest first, at most `max`
// classes: shares of every point as the picture's legend gives them, points without finite
// coordinates on their own (the server labels them unknown), always named when there are any.
std::string label_histogram(const PointCloud& labeled, int max = 4);

}  // namespace primlabel::client::tools
