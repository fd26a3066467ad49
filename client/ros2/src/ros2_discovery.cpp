#include "primlabel/ros2/ros2_discovery.hpp"

#include <cctype>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace primlabel::ros2node {

namespace {

constexpr std::size_t kMaxStaticPeers = 32;

std::string variable(const char* name) {
  const char* value = std::getenv(name);
  return value ? value : "";
}

// A host name, IPv4 or IPv6 address (optionally with a port): what an XML attribute can hold
// as it is.
bool is_host(const std::string& peer) {
  if (peer.empty() || peer.size() > 255) return false;
  for (const char c : peer)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != ':' &&
        c != '_' && c != '[' && c != ']')
      return false;
  return true;
}

std::vector<std::string> peers_of(const std::string& list) {
  std::vector<std::string> peers;
  std::istringstream in(list);
  std::string peer;
  while (std::getline(in, peer, ';')) {
    const auto first = peer.find_first_not_of(' ');
    if (first == std::string::npos) continue;
    peer = peer.substr(first, peer.find_last_not_of(' ') - first + 1);
    if (!is_host(peer))
      throw std::invalid_argument("ROS_STATIC_PEERS: '" + peer +
                                  "' is not a host name or address (peers are separated by ';')");
    peers.push_back(peer);
  }
  if (peers.size() > kMaxStaticPeers)
    throw std::invalid_argument("ROS_STATIC_PEERS: more than " + std::to_string(kMaxStaticPeers) +
                                " peers");
  return peers;
}

}  // namespace

DiscoveryEnvironment discovery_environment() {
  return {variable("ROS_LOCALHOST_ONLY"), variable("ROS_AUTOMATIC_DISCOVERY_RANGE"),
          variable("ROS_STATIC_PEERS"), variable("CYCLONEDDS_URI")};
}

std::string cyclone_config(const DiscoveryEnvironment& e) {
  if (e.localhost_only != "" && e.localhost_only != "0" && e.localhost_only != "1")
    throw std::invalid_argument("ROS_LOCALHOST_ONLY must be 0 or 1, not '" + e.localhost_only +
                                "'");
  std::string range = e.discovery_range.empty() ? "SUBNET" : e.discovery_range;
  if (range != "SUBNET" && range != "LOCALHOST" && range != "OFF" && range != "SYSTEM_DEFAULT")
    throw std::invalid_argument(
        "ROS_AUTOMATIC_DISCOVERY_RANGE must be SUBNET, LOCALHOST, OFF or "
        "SYSTEM_DEFAULT, not '" +
        e.discovery_range + "'");
  std::vector<std::string> peers = peers_of(e.static_peers);
  if (e.localhost_only == "1") {
    range = "LOCALHOST";
    peers.clear();
  }

  std::string general, discovery;
  if (range == "LOCALHOST")
    general = "<Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>";
  else if (range == "OFF")
    general = "<AllowMulticast>false</AllowMulticast>";
  if (!peers.empty()) {
    // Peers are reached on the ports of participant indices, so the node takes one too.
    discovery = "<ParticipantIndex>auto</ParticipantIndex><Peers>";
    for (const std::string& peer : peers) discovery += "<Peer address=\"" + peer + "\"/>";
    discovery += "</Peers>";
  }
  if (general.empty() && discovery.empty()) return {};
  std::string config = "<CycloneDDS><Domain Id=\"any\">";
  if (!general.empty()) config += "<General>" + general + "</General>";
  if (!discovery.empty()) config += "<Discovery>" + discovery + "</Discovery>";
  config += "</Domain></CycloneDDS>";
  if (!e.cyclonedds_uri.empty()) config += "," + e.cyclonedds_uri;
  return config;
}

}  // namespace primlabel::ros2node
