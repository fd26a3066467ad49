#pragma once
// One cloud in, the labeled cloud and the summary out: the step every node (ROS 1, ROS 2 over
// DDS, rclcpp) takes per message, without its middleware. The node converts its message to a
// PointCloud2View, publishes what comes back and logs the notes in its own way.

#include <optional>
#include <string>

#include "primlabel/client/client.hpp"
#include "primlabel/ros_common/labeled_pointcloud2.hpp"
#include "primlabel/ros_common/node_parameters.hpp"
#include "primlabel/ros_common/pointcloud2.hpp"

namespace primlabel::roscommon {

struct LabeledCloud {
  PointCloud2Data cloud;     // the input with `label` and the asked-for fields
  std::string summary_json;  // the call's LabelSummary (summary_json.hpp)
  std::size_t points = 0;
  std::string request_id;
  // Notes for the node's log: which model labels the clouds and why, when that changed since
  // the last cloud; the server's domain warning (empty: none).
  std::optional<std::string> model_change;
  std::string domain_warning;
};

class CloudLabeler {
 public:
  // Throws as client_options (an unreadable token file).
  explicit CloudLabeler(const NodeParameters& parameters);

  // Labels `cloud` through the service. Throws std::exception with the reason when the cloud's
  // layout cannot be read or the call fails (a ClientError's text starts with the status code);
  // the labeler stays usable for the next cloud either way.
  LabeledCloud label(const PointCloud2View& cloud);

 private:
  client::Client client_;
  client::LabelOptions label_options_;
  LabeledFields fields_;
  std::string last_model_;  // "name version" of the last answer, to note its choice once
};

}  // namespace primlabel::roscommon
