#pragma once
// The labeling nodes' parameters (server, model, ...; README: client/ros/README.md and
// client/ros2/README.md), the same for ROS 1 and ROS 2, and the client options they make. Each
// node reads them its own way (ROS 1: the parameter server; ROS 2: the command line).

#include <array>
#include <optional>
#include <string>

#include "primlabel/client/client.hpp"

namespace primlabel::roscommon {

struct NodeParameters {
  // The service.
  std::string server = "127.0.0.1:50051";  // HOST[:PORT]; HOST alone means port 50051
  std::string token;                       // bearer token; else token_file, else $PRIMLABEL_TOKEN
  std::string token_file;                  // a file holding the token
  bool tls = false;  // TLS with the system's roots (implied by tls_ca, tls_cert, tls_key)
  std::string tls_ca, tls_cert, tls_key, tls_server_name;
  double deadline = 10.0;  // seconds a call may take, its retries included
  int retries = 4;         // attempts in all when the server is unavailable
  // The labeling.
  std::string model;          // empty = the server's default model
  std::string model_version;  // empty = the latest loaded
  double voxel_size = 0.0;    // > 0: downsample first (m); 0 = the model's setting
  // The unit of the clouds' coordinates: "m" (REP 103, the default), "cm" or "mm" (some depth
  // drivers); points and viewpoint are scaled to metres for the service, the published cloud
  // keeps the input's coordinates.
  std::string units = "m";
  // Describe and infer every point: no plane cascade (the summary's cascaded_points stays 0),
  // the model's exact labels everywhere, slower.
  bool every_point = false;
  // The sensor's position in the cloud's frame, for orienting normals; unset = the frame's
  // origin (right for a cloud in its camera's own frame, wrong for one in base_link or map).
  std::optional<std::array<double, 3>> viewpoint;
  bool tabletop_only = false;
  // With tabletop_only: the table and its objects as instances in the summary and a uint32
  // `object` field per point (0 the table, k the summary's objects[k - 1]).
  bool objects = false;
  // Fitted primitive instances in the summary and a uint32 `segment` field per point (its index
  // into the summary's primitives).
  bool primitives = false;
  bool confidence = false;     // publish a float32 `confidence` field (the highest probability)
  bool probabilities = false;  // publish float32 `prob_<class>` fields
  // Topics, resolved in the node's namespace.
  std::string input_topic = "points";
  std::string output_topic = "points_labeled";
  std::string summary_topic = "points_labeled_summary";
};

// Checks `parameters` once read and writes the server address with its port. Throws
// std::invalid_argument naming the parameter (as `prefix` + name: "~voxel_size" for ROS 1's
// private parameters): a negative or non-finite voxel size, units other than m, cm and mm, a
// deadline <= 0, retries < 1, an empty topic, a malformed server address, objects without
// tabletop_only.
void check_parameters(NodeParameters& parameters, const std::string& prefix);

// The connection: address, deadline, retries, TLS and the bearer token (read from token_file or
// $PRIMLABEL_TOKEN when token is empty; throws std::runtime_error when the file is unreadable).
client::ClientOptions client_options(const NodeParameters& parameters);

// What every cloud is labeled with; probabilities are asked for when either output needs them.
client::LabelOptions label_options(const NodeParameters& parameters);

// The labeling settings for the start-up line, every one named with its value ("model
// tabletop-kinect, tabletop_only false, every_point false, voxel_size the model's, ..."): a
// parameter server keeps private parameters from the last run, so a stale tabletop_only must
// show.
std::string settings_text(const NodeParameters& parameters);

}  // namespace primlabel::roscommon
