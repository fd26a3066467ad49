#pragma once
// ROS 2's discovery variables as rmw_cyclonedds turns them into Cyclone DDS configuration, so the
// node finds the same peers as the robot's own nodes:
//   ROS_LOCALHOST_ONLY=1 (Humble; deprecated later, where it means the localhost range) and
//   ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST: only the loopback interface (127.0.0.1);
//   ROS_AUTOMATIC_DISCOVERY_RANGE=OFF: no multicast, only the static peers;
//   SUBNET (the default) and SYSTEM_DEFAULT: Cyclone DDS's own discovery (multicast);
//   ROS_STATIC_PEERS="a;b": unicast discovery of those hosts as well (ignored, as by rcl, when
//   ROS_LOCALHOST_ONLY=1).
// CYCLONEDDS_URI comes after that fragment, so where it sets the same thing it wins, as with
// rmw_cyclonedds.

#include <string>

namespace primlabel::ros2node {

struct DiscoveryEnvironment {
  std::string localhost_only;   // ROS_LOCALHOST_ONLY
  std::string discovery_range;  // ROS_AUTOMATIC_DISCOVERY_RANGE
  std::string static_peers;     // ROS_STATIC_PEERS
  std::string cyclonedds_uri;   // CYCLONEDDS_URI
};

// This process's variables (unset = empty).
DiscoveryEnvironment discovery_environment();

// The configuration for dds_create_domain: the fragment the variables make, then CYCLONEDDS_URI
// (comma-separated, as Cyclone DDS reads a list). Empty when no variable asks for anything:
// then Cyclone DDS reads CYCLONEDDS_URI itself. Throws std::invalid_argument naming the variable
// for a value ROS 2 does not define (ROS_LOCALHOST_ONLY other than 0 or 1, an unknown range, a
// peer that is not a host name or address, more than 32 peers).
std::string cyclone_config(const DiscoveryEnvironment& environment);

}  // namespace primlabel::ros2node
