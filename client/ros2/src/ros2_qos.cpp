#include "ros2_qos.hpp"

namespace primlabel::ros2node {

namespace {

Qos profile(dds_reliability_kind_t reliability, int depth) {
  Qos qos(dds_create_qos());
  dds_qset_reliability(qos.get(), reliability, DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

// A writer sends plain CDR (XCDR1), as rmw_cyclonedds does for ROS 2 messages; a reader takes
// that and XCDR2, so a peer on a newer DDS that offers XCDR2 still matches.
Qos writing(Qos qos) {
  const dds_data_representation_id_t xcdr1[] = {DDS_DATA_REPRESENTATION_XCDR1};
  dds_qset_data_representation(qos.get(), 1, xcdr1);
  return qos;
}
Qos reading(Qos qos) {
  const dds_data_representation_id_t either[] = {DDS_DATA_REPRESENTATION_XCDR1,
                                                 DDS_DATA_REPRESENTATION_XCDR2};
  dds_qset_data_representation(qos.get(), 2, either);
  return qos;
}

}  // namespace

Qos sensor_data_qos() { return profile(DDS_RELIABILITY_BEST_EFFORT, 5); }
Qos default_qos() { return profile(DDS_RELIABILITY_RELIABLE, 10); }
Qos input_reader_qos() { return reading(profile(DDS_RELIABILITY_BEST_EFFORT, 1)); }
Qos output_writer_qos() { return writing(profile(DDS_RELIABILITY_RELIABLE, 1)); }

}  // namespace primlabel::ros2node
