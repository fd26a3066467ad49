#pragma once
// ROS 2's QoS profiles as DDS QoS, and the node's choice between them: it reads best effort (so
// both a sensor driver's best-effort and a reliable publisher match) and writes reliable (so both
// a default, reliable subscriber and a sensor-data, best-effort one match). A robot changes the
// node's choice per topic with ROS 2's QoS override parameters (QosOverrides).

#include <dds/dds.h>

#include <memory>
#include <optional>
#include <string>

namespace primlabel::ros2node {

struct QosDeleter {
  void operator()(dds_qos_t* qos) const { dds_delete_qos(qos); }
};
using Qos = std::unique_ptr<dds_qos_t, QosDeleter>;

// The most samples an endpoint keeps (a depth, or keep_all's limit): 100 Kinect frames are
// ~500 MB, so a robot's override cannot make the node's memory unbounded.
constexpr int kMaxQueuedSamples = 100;

// One endpoint's `qos_overrides.<topic>.<publisher|subscription>.<policy>` parameters, as rclcpp
// applies them; an unset policy keeps the node's choice.
struct QosOverrides {
  std::optional<dds_reliability_kind_t> reliability;
  std::optional<dds_history_kind_t> history;
  std::optional<int> depth;  // 1..kMaxQueuedSamples
  std::optional<dds_durability_kind_t> durability;
};

// rclcpp::SensorDataQoS: best effort, keep last 5, volatile.
Qos sensor_data_qos();
// rclcpp's default (rmw_qos_profile_default): reliable, keep last 10, volatile.
Qos default_qos();

// The input reader: best effort, keep last 1, so while a cloud is labeled a newer one replaces
// the one waiting (the ROS 1 node's queue of one: skip scans, never fall behind). A robot that
// publishes reliably and wants every frame overrides reliability (and depth).
Qos input_reader_qos(const QosOverrides& overrides = {});
// The output writers: reliable, keep last 1 (a slow subscriber gets the newest, the node never
// blocks on it), volatile.
Qos output_writer_qos(const QosOverrides& overrides = {});

// "reliable, keep last 10, volatile": the policies a start-up line shows.
std::string qos_text(const dds_qos_t* qos);

// Iron's and later's USER_DATA of an endpoint: `typehash=RIHS01_...;` (type_hash.hpp).
void set_type_hash(dds_qos_t* qos, const std::string& type_hash);

}  // namespace primlabel::ros2node
