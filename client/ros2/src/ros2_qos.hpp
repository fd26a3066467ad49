#pragma once
// ROS 2's QoS profiles as DDS QoS, and the node's choice between them: it reads best effort (so
// both a sensor driver's best-effort and a reliable publisher match) and writes reliable (so both
// a default, reliable subscriber and a sensor-data, best-effort one match).

#include <dds/dds.h>

#include <memory>

namespace primlabel::ros2node {

struct QosDeleter {
  void operator()(dds_qos_t* qos) const { dds_delete_qos(qos); }
};
using Qos = std::unique_ptr<dds_qos_t, QosDeleter>;

// rclcpp::SensorDataQoS: best effort, keep last 5, volatile.
Qos sensor_data_qos();
// rclcpp's default (rmw_qos_profile_default): reliable, keep last 10, volatile.
Qos default_qos();

// The input reader: best effort, keep last 1, so while a cloud is labeled a newer one replaces
// the one waiting (the ROS 1 node's queue of one: skip scans, never fall behind).
Qos input_reader_qos();
// The output writers: reliable, keep last 1 (a slow subscriber gets the newest, the node never
// blocks on it), volatile.
Qos output_writer_qos();

}  // namespace primlabel::ros2node
