#include "primlabel/ros2/ros_discovery_info.hpp"

#include <algorithm>
#include <cstring>

#include "primlabel/ros2/ros2_qos.hpp"
#include "primlabel/ros2/type_hash.hpp"
#include "rmw_dds_common/msg/ParticipantEntitiesInfo.h"
#include "rmw_dds_common/msg/ParticipantEntitiesInfoHumble.h"

namespace primlabel::ros2node {

namespace {

constexpr const char* kTopic = "ros_discovery_info";  // no "rt/": rmw's own topic
constexpr const char* kTypeName = "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_";

// Humble's layout registered under the one DDS type name both layouts have.
const dds_topic_descriptor_t* humble_descriptor() {
  static const dds_topic_descriptor_t descriptor = [] {
    dds_topic_descriptor_t d = rmw_dds_common_humble_msg_dds__ParticipantEntitiesInfo__desc;
    d.m_typename = kTypeName;
    return d;
  }();
  return &descriptor;
}

template <class Gid>
Gid gid_of(const std::array<std::uint8_t, 16>& guid) {
  Gid gid{};  // zero after the 16 bytes in Humble's 24
  std::memcpy(gid.data, guid.data(), guid.size());
  return gid;
}

}  // namespace

std::array<std::uint8_t, 16> guid_of(dds_entity_t entity) {
  dds_guid_t guid;
  checked(dds_get_guid(entity, &guid), "DDS GUID");
  std::array<std::uint8_t, 16> out;
  std::memcpy(out.data(), guid.v, out.size());
  return out;
}

RosDiscoveryInfo::RosDiscoveryInfo(dds_entity_t participant, bool humble)
    : participant_(participant), humble_(humble) {
  const dds_entity_t topic =
      checked(dds_create_topic(participant,
                               humble ? humble_descriptor()
                                      : &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc,
                               kTopic, nullptr, nullptr),
              std::string("DDS topic ") + kTopic);
  QosOverrides discovery;
  discovery.reliability = DDS_RELIABILITY_RELIABLE;
  discovery.depth = 1;
  discovery.durability = DDS_DURABILITY_TRANSIENT_LOCAL;
  const Qos qos = output_writer_qos(discovery);
  if (!humble) set_type_hash(qos.get(), participant_entities_info_type_hash());
  writer_ = DdsEntity(checked(dds_create_writer(participant, topic, qos.get(), nullptr),
                              std::string("DDS writer on ") + kTopic));
}

void RosDiscoveryInfo::announce(const std::string& node_namespace, const std::string& name,
                                const std::vector<dds_entity_t>& readers,
                                const std::vector<dds_entity_t>& writers) {
  node_namespace_ = node_namespace;
  name_ = name;
  readers_.clear();
  writers_.clear();
  for (const dds_entity_t r : readers) readers_.push_back(guid_of(r));
  for (const dds_entity_t w : writers) writers_.push_back(guid_of(w));
  if (humble_)
    write<rmw_dds_common_humble_msg_dds__ParticipantEntitiesInfo_,
          rmw_dds_common_humble_msg_dds__NodeEntitiesInfo_, rmw_dds_common_humble_msg_dds__Gid_>(
        true);
  else
    write<rmw_dds_common_msg_dds__ParticipantEntitiesInfo_,
          rmw_dds_common_msg_dds__NodeEntitiesInfo_, rmw_dds_common_msg_dds__Gid_>(true);
}

void RosDiscoveryInfo::withdraw() {
  if (humble_)
    write<rmw_dds_common_humble_msg_dds__ParticipantEntitiesInfo_,
          rmw_dds_common_humble_msg_dds__NodeEntitiesInfo_, rmw_dds_common_humble_msg_dds__Gid_>(
        false);
  else
    write<rmw_dds_common_msg_dds__ParticipantEntitiesInfo_,
          rmw_dds_common_msg_dds__NodeEntitiesInfo_, rmw_dds_common_msg_dds__Gid_>(false);
}

template <class Info, class Node, class Gid>
void RosDiscoveryInfo::write(bool with_node) const {
  std::vector<Gid> readers, writers;
  for (const auto& g : readers_) readers.push_back(gid_of<Gid>(g));
  for (const auto& g : writers_) writers.push_back(gid_of<Gid>(g));
  Node node{};
  // The names fit: parse_arguments refuses a namespace or name longer than the message's bound.
  std::strncpy(node.node_namespace, node_namespace_.c_str(), sizeof node.node_namespace - 1);
  std::strncpy(node.node_name, name_.c_str(), sizeof node.node_name - 1);
  node.reader_gid_seq._length = node.reader_gid_seq._maximum =
      static_cast<std::uint32_t>(readers.size());
  node.reader_gid_seq._buffer = readers.data();
  node.writer_gid_seq._length = node.writer_gid_seq._maximum =
      static_cast<std::uint32_t>(writers.size());
  node.writer_gid_seq._buffer = writers.data();
  Info info{};
  info.gid = gid_of<Gid>(guid_of(participant_));
  info.node_entities_info_seq._length = info.node_entities_info_seq._maximum = with_node ? 1 : 0;
  info.node_entities_info_seq._buffer = with_node ? &node : nullptr;
  checked(dds_write(writer_.get(), &info), std::string("writing ") + kTopic);
}

}  // namespace primlabel::ros2node
