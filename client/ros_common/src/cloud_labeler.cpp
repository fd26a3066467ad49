#include "primlabel/ros_common/cloud_labeler.hpp"

#include "primlabel/ros_common/pointcloud2_xyz.hpp"
#include "primlabel/ros_common/summary_json.hpp"

namespace primlabel::roscommon {

CloudLabeler::CloudLabeler(const NodeParameters& parameters)
    : client_(client_options(parameters)),
      label_options_(label_options(parameters)),
      fields_{parameters.confidence, parameters.probabilities, parameters.objects,
              parameters.primitives} {}

LabeledCloud CloudLabeler::label(const PointCloud2View& cloud) {
  const PointCloud points = xyz_from_pointcloud2(cloud);
  client::LabelOptions options = label_options_;
  options.frame_id = cloud.frame_id;
  options.stamp_ns = cloud.stamp_ns;
  // The server's log lines name the scan.
  options.scan_id = cloud.frame_id + "@" + std::to_string(cloud.stamp_ns);
  const client::LabelResult result = client_.label(points, options);

  LabeledCloud out;
  out.cloud = labeled_pointcloud2(cloud, result, fields_);
  out.summary_json = summary_json(result.summary);
  out.points = result.size();
  out.request_id = result.summary.request_id();
  out.domain_warning = result.summary.domain_warning();
  // Which model labels the clouds, and why, each time it changes (not every frame).
  const std::string model = result.summary.model() + " " + result.summary.model_version();
  if (model != last_model_) {
    last_model_ = model;
    out.model_change = "model " + model + " labels frame '" + cloud.frame_id + "' (" +
                       client::model_choice_text(result.summary) + ")";
  }
  return out;
}

}  // namespace primlabel::roscommon
