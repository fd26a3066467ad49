// primlabel::ros2node::LabelingComponent: the labeling bridge (client/ros_common) as an rclcpp
// component, for a ROS 2 installation (client/ros2/README.md). The same parameters, topics,
// fields, summary and QoS overrides as primlabel-ros2; ROS 2's own parameters (files, -p,
// use_sim_time), names, logging, graph and QoS instead of the node's DDS plumbing. Not built on
// Debian 12 (no rclcpp) and so not verified there.

#include <exception>
#include <memory>
#include <optional>
#include <rclcpp/rclcpp.hpp>
#include <rclcpp_components/register_node_macro.hpp>
#include <sensor_msgs/msg/point_cloud2.hpp>
#include <std_msgs/msg/string.hpp>
#include <string>
#include <utility>

#include "primlabel/ros_common/cloud_labeler.hpp"
#include "primlabel/ros_common/pointcloud2_body.hpp"

namespace primlabel::ros2node {

namespace {

roscommon::PointCloud2View view_of(const sensor_msgs::msg::PointCloud2& m) {
  roscommon::PointCloud2View view = roscommon::view_of_body(m);
  view.frame_id = m.header.frame_id;
  view.stamp_ns = m.header.stamp.sec < 0
                      ? 0
                      : std::uint64_t(m.header.stamp.sec) * 1'000'000'000u + m.header.stamp.nanosec;
  return view;
}

sensor_msgs::msg::PointCloud2 to_message(roscommon::PointCloud2Data&& cloud) {
  std::string frame_id = std::move(cloud.frame_id);
  const std::uint64_t stamp_ns = cloud.stamp_ns;
  auto m = roscommon::message_body<sensor_msgs::msg::PointCloud2>(std::move(cloud));
  m.header.frame_id = std::move(frame_id);
  m.header.stamp.sec = static_cast<std::int32_t>(stamp_ns / 1'000'000'000u);
  m.header.stamp.nanosec = static_cast<std::uint32_t>(stamp_ns % 1'000'000'000u);
  return m;
}

}  // namespace

class LabelingComponent : public rclcpp::Node {
 public:
  explicit LabelingComponent(const rclcpp::NodeOptions& options)
      : rclcpp::Node("primlabel_ros2", options),
        parameters_(declared_parameters()),
        labeler_(parameters_) {
    // Reliable output matches default and sensor-data subscribers; best-effort input, keep last 1
    // matches either publisher and skips scans rather than falling behind (as primlabel-ros2).
    // The same qos_overrides.<topic>.<publisher|subscription>.<policy> parameters as
    // primlabel-ros2 change them (e.g. reliable input for a reliable publisher's large frames).
    const rclcpp::QosOverridingOptions overridable(
        {rclcpp::QosPolicyKind::Reliability, rclcpp::QosPolicyKind::History,
         rclcpp::QosPolicyKind::Depth, rclcpp::QosPolicyKind::Durability});
    rclcpp::PublisherOptions publisher_options;
    publisher_options.qos_overriding_options = overridable;
    rclcpp::SubscriptionOptions subscription_options;
    subscription_options.qos_overriding_options = overridable;
    const rclcpp::QoS output_qos = rclcpp::QoS(rclcpp::KeepLast(1)).reliable();
    cloud_publisher_ = create_publisher<sensor_msgs::msg::PointCloud2>(
        parameters_.output_topic, output_qos, publisher_options);
    summary_publisher_ = create_publisher<std_msgs::msg::String>(parameters_.summary_topic,
                                                                 output_qos, publisher_options);
    subscription_ = create_subscription<sensor_msgs::msg::PointCloud2>(
        parameters_.input_topic, rclcpp::SensorDataQoS().keep_last(1),
        [this](sensor_msgs::msg::PointCloud2::ConstSharedPtr cloud) { on_cloud(*cloud); },
        subscription_options);
    RCLCPP_INFO(get_logger(), "labeling %s -> %s (summary %s) through %s: %s",
                subscription_->get_topic_name(), cloud_publisher_->get_topic_name(),
                summary_publisher_->get_topic_name(), parameters_.server.c_str(),
                roscommon::settings_text(parameters_).c_str());
  }

 private:
  roscommon::NodeParameters declared_parameters() {
    roscommon::NodeParameters p;
    p.server = declare_parameter("server", p.server);
    p.token = declare_parameter("token", p.token);
    p.token_file = declare_parameter("token_file", p.token_file);
    p.tls = declare_parameter("tls", p.tls);
    p.tls_ca = declare_parameter("tls_ca", p.tls_ca);
    p.tls_cert = declare_parameter("tls_cert", p.tls_cert);
    p.tls_key = declare_parameter("tls_key", p.tls_key);
    p.tls_server_name = declare_parameter("tls_server_name", p.tls_server_name);
    p.deadline = declare_parameter("deadline", p.deadline);
    p.retries = static_cast<int>(declare_parameter("retries", std::int64_t{p.retries}));
    p.model = declare_parameter("model", p.model);
    p.model_version = declare_parameter("model_version", p.model_version);
    p.voxel_size = declare_parameter("voxel_size", p.voxel_size);
    p.every_point = declare_parameter("every_point", p.every_point);
    const auto viewpoint = declare_parameter("viewpoint", std::vector<double>{});
    if (viewpoint.size() == 3)
      p.viewpoint = std::array<double, 3>{viewpoint[0], viewpoint[1], viewpoint[2]};
    else if (!viewpoint.empty())
      throw std::invalid_argument("viewpoint must be three numbers [x, y, z]");
    p.tabletop_only = declare_parameter("tabletop_only", p.tabletop_only);
    p.objects = declare_parameter("objects", p.objects);
    p.primitives = declare_parameter("primitives", p.primitives);
    p.confidence = declare_parameter("confidence", p.confidence);
    p.probabilities = declare_parameter("probabilities", p.probabilities);
    p.input_topic = declare_parameter("input_topic", p.input_topic);
    p.output_topic = declare_parameter("output_topic", p.output_topic);
    p.summary_topic = declare_parameter("summary_topic", p.summary_topic);
    roscommon::check_parameters(p, "");
    return p;
  }

  void on_cloud(const sensor_msgs::msg::PointCloud2& cloud) {
    try {
      roscommon::LabeledCloud labeled = labeler_.label(view_of(cloud));
      if (!labeled.domain_warning.empty())
        RCLCPP_WARN_THROTTLE(get_logger(), *get_clock(), 60000, "%s",
                             labeled.domain_warning.c_str());
      if (labeled.model_change) RCLCPP_INFO(get_logger(), "%s", labeled.model_change->c_str());
      cloud_publisher_->publish(to_message(std::move(labeled.cloud)));
      std_msgs::msg::String summary;
      summary.data = std::move(labeled.summary_json);
      summary_publisher_->publish(summary);
    } catch (const std::exception& e) {
      RCLCPP_ERROR(get_logger(), "cloud of frame '%s' (stamp %d.%09u) not labeled: %s",
                   cloud.header.frame_id.c_str(), cloud.header.stamp.sec,
                   cloud.header.stamp.nanosec, e.what());
    }
  }

  roscommon::NodeParameters parameters_;
  roscommon::CloudLabeler labeler_;
  rclcpp::Publisher<sensor_msgs::msg::PointCloud2>::SharedPtr cloud_publisher_;
  rclcpp::Publisher<std_msgs::msg::String>::SharedPtr summary_publisher_;
  rclcpp::Subscription<sensor_msgs::msg::PointCloud2>::SharedPtr subscription_;
};

}  // namespace primlabel::ros2node

RCLCPP_COMPONENTS_REGISTER_NODE(primlabel::ros2node::LabelingComponent)
