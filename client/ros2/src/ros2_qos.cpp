#include "ros2_qos.hpp"

namespace primlabel::ros2node {

namespace {

Qos profile(dds_reliability_kind_t reliability, int depth) {
  Qos qos(dds_create_qos());
  dds_qset_reliability(qos.get(), reliability, DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  // Plain CDR (XCDR1), the representation rmw_cyclonedds uses for ROS 2 messages.
  const dds_data_representation_id_t xcdr1[] = {DDS_DATA_REPRESENTATION_XCDR1};
  dds_qset_data_representation(qos.get(), 1, xcdr1);
  return qos;
}

}  // namespace

Qos sensor_data_qos() { return profile(DDS_RELIABILITY_BEST_EFFORT, 5); }
Qos default_qos() { return profile(DDS_RELIABILITY_RELIABLE, 10); }
Qos input_reader_qos() { return profile(DDS_RELIABILITY_BEST_EFFORT, 1); }
Qos output_writer_qos() { return profile(DDS_RELIABILITY_RELIABLE, 1); }

}  // namespace primlabel::ros2node
