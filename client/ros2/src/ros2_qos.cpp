#include "primlabel/ros2/ros2_qos.hpp"

namespace primlabel::ros2node {

namespace {

// rmw_cyclonedds blocks a reliable writer without limit (DDS_INFINITY); the node's writers give
// up after 100 ms, so a subscriber that stops reading cannot stall the labeling.
constexpr dds_duration_t kMaxBlocking = DDS_MSECS(100);

Qos profile(dds_reliability_kind_t reliability, int depth) {
  Qos qos(dds_create_qos());
  dds_qset_reliability(qos.get(), reliability, kMaxBlocking);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

Qos overridden(Qos qos, const QosOverrides& o) {
  if (o.reliability) dds_qset_reliability(qos.get(), *o.reliability, kMaxBlocking);
  dds_history_kind_t history = DDS_HISTORY_KEEP_LAST;
  int32_t depth = 1;
  dds_qget_history(qos.get(), &history, &depth);
  if (o.history) history = *o.history;
  if (o.depth) depth = *o.depth;
  dds_qset_history(qos.get(), history, depth);
  if (history == DDS_HISTORY_KEEP_ALL)  // keep all, but never more than the bound
    dds_qset_resource_limits(qos.get(), kMaxQueuedSamples, DDS_LENGTH_UNLIMITED,
                             DDS_LENGTH_UNLIMITED);
  if (o.durability) dds_qset_durability(qos.get(), *o.durability);
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
Qos input_reader_qos(const QosOverrides& overrides) {
  return reading(overridden(profile(DDS_RELIABILITY_BEST_EFFORT, 1), overrides));
}
Qos output_writer_qos(const QosOverrides& overrides) {
  return writing(overridden(profile(DDS_RELIABILITY_RELIABLE, 1), overrides));
}

std::string qos_text(const dds_qos_t* qos) {
  dds_reliability_kind_t reliability = DDS_RELIABILITY_BEST_EFFORT;
  dds_duration_t blocking = 0;
  dds_history_kind_t history = DDS_HISTORY_KEEP_LAST;
  int32_t depth = 1;
  dds_durability_kind_t durability = DDS_DURABILITY_VOLATILE;
  dds_qget_reliability(qos, &reliability, &blocking);
  dds_qget_history(qos, &history, &depth);
  dds_qget_durability(qos, &durability);
  return std::string(reliability == DDS_RELIABILITY_RELIABLE ? "reliable" : "best effort") +
         (history == DDS_HISTORY_KEEP_ALL ? ", keep all" : ", keep last " + std::to_string(depth)) +
         (durability == DDS_DURABILITY_TRANSIENT_LOCAL ? ", transient local" : ", volatile");
}

void set_type_hash(dds_qos_t* qos, const std::string& type_hash) {
  const std::string user_data = "typehash=" + type_hash + ";";
  dds_qset_userdata(qos, user_data.data(), user_data.size());
}

}  // namespace primlabel::ros2node
