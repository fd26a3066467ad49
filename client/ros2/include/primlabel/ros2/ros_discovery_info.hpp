#pragma once
// The node in ROS 2's graph. rmw publishes, per DDS participant, its nodes and the GIDs of each
// node's readers and writers on the DDS topic `ros_discovery_info`
// (rmw_dds_common/msg/ParticipantEntitiesInfo; reliable, transient local, keep last 1, so a tool
// that starts later still gets it). `ros2 node list` and `ros2 node info` read it; a node
// missing there is invisible to them even when its topics are seen.

#include <dds/dds.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "primlabel/ros2/dds_entity.hpp"

namespace primlabel::ros2node {

// An entity's DDS GUID (participant prefix and entity id), which rmw_cyclonedds uses as its GID.
std::array<std::uint8_t, 16> guid_of(dds_entity_t entity);

class RosDiscoveryInfo {
 public:
  // A writer on ros_discovery_info in `participant`. `humble`: Humble's layout (24-byte GIDs)
  // and no type hash; else Iron's and later's (16 bytes, a type hash in USER_DATA).
  RosDiscoveryInfo(dds_entity_t participant, bool humble);
  // Publishes the participant with one node, `name` in `node_namespace`, and its endpoints.
  void announce(const std::string& node_namespace, const std::string& name,
                const std::vector<dds_entity_t>& readers, const std::vector<dds_entity_t>& writers);
  // Publishes the participant without its node, as rmw does when a node is destroyed.
  void withdraw();

 private:
  template <class Info, class Node, class Gid>
  void write(bool with_node) const;

  dds_entity_t participant_;
  bool humble_;
  DdsEntity writer_;
  std::string node_namespace_, name_;
  std::vector<std::array<std::uint8_t, 16>> readers_, writers_;
};

}  // namespace primlabel::ros2node
