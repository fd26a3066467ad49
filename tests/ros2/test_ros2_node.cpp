// ros2.LabelsPointCloud2: primlabel-ros2 between Cyclone DDS peers that play the robot and a real
// primlabel-server, all on 127.0.0.1. This process writes sensor_msgs/msg/PointCloud2 samples
// with ROS 2's DDS type and topic names (sensor_msgs::msg::dds_::PointCloud2_ on rt/<name>), on a
// domain of its own with Cyclone DDS held to the loopback interface, and reads the labeled cloud
// and the summary back as a ROS 2 subscriber would. Checks: the labels and probabilities equal
// `primlabel label` on the same file point for point, the input's bytes and the echoed frame and
// stamp; bad clouds are logged and skipped; a server that is down is logged and the node labels
// once it is back; a burst leaves the node alive with the newest cloud labeled. As a ROS 2 user
// meets it: the node starts from a parameters file, is found with ROS_LOCALHOST_ONLY=1 and no
// CYCLONEDDS_URI, is listed in ros_discovery_info under its name with its endpoints' GIDs and
// type hashes, and with a reliable-input QoS override labels 10 of 10 whole Kinect frames from a
// reliable keep-last-10 publisher under Cyclone DDS's default buffers. Every wait is bounded;
// every process is killed.

#include <dds/dds.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/model/label_model.hpp"
#include "process.hpp"
#include "random_label_model.hpp"
#include "rmw_dds_common/msg/ParticipantEntitiesInfo.h"
#include "sensor_msgs/msg/PointCloud2.h"
#include "std_msgs/msg/String.h"
#include "test_util.hpp"

namespace primlabel::ros2test {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::Process;

constexpr float kVoxel = 0.005f;  // the node's voxel_size and the CLI's --voxel-size

// A received PointCloud2, copied out of DDS's sample.
struct Cloud {
  std::string frame_id;
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::uint32_t height = 0, width = 0, point_step = 0, row_step = 0;
  std::vector<std::pair<std::string, std::uint32_t>> fields;  // name, offset
  std::vector<std::uint8_t> data;
  std::uint32_t offset_of(const std::string& name) const {
    for (const auto& [n, offset] : fields)
      if (n == name) return offset;
    throw std::out_of_range("no field " + name);
  }
  template <class T>
  T value(std::size_t i, const std::string& name) const {
    T v;
    std::memcpy(&v, data.data() + i * point_step + offset_of(name), sizeof v);
    return v;
  }
};

// One sample to send: x y z float32 and 4 bytes of padding (PCL's layout), the cloud's width
// and height (an organised frame stays organised).
struct Outgoing {
  std::vector<sensor_msgs_msg_dds__PointField_> fields;
  std::vector<std::uint8_t> data;
  std::string frame_id;
  sensor_msgs_msg_dds__PointCloud2_ message{};
};

std::unique_ptr<Outgoing> outgoing(const PointCloud& cloud, const std::string& frame,
                                   std::int32_t sec, std::uint32_t nanosec) {
  auto m = std::make_unique<Outgoing>();
  static const char* names[] = {"x", "y", "z"};
  for (std::uint32_t k = 0; k < 3; ++k)
    m->fields.push_back({const_cast<char*>(names[k]), 4 * k, 7 /* FLOAT32 */, 1});
  m->data.assign(cloud.size() * 16, 0xAB);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    std::memcpy(m->data.data() + 16 * i, cloud.xyz[i].data(), 12);
  m->frame_id = frame;
  auto& msg = m->message;
  msg.header.stamp.sec = sec;
  msg.header.stamp.nanosec = nanosec;
  msg.header.frame_id = m->frame_id.data();
  const bool organised =
      cloud.height > 1 && std::size_t(cloud.width) * cloud.height == cloud.size();
  msg.height = organised ? cloud.height : 1;
  msg.width = organised ? cloud.width : static_cast<std::uint32_t>(cloud.size());
  msg.fields._length = msg.fields._maximum = 3;
  msg.fields._buffer = m->fields.data();
  msg.is_bigendian = false;
  msg.point_step = 16;
  msg.row_step = 16 * msg.width;
  msg.data._length = msg.data._maximum = static_cast<std::uint32_t>(m->data.size());
  msg.data._buffer = m->data.data();
  msg.is_dense = count_finite(cloud) == cloud.size();
  return m;
}

dds_qos_t* qos(dds_reliability_kind_t reliability, int depth) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, reliability, DDS_MSECS(100));
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
  return q;
}

// The robot's side: a writer on rt/<node>/in and readers on rt/<node>/out and rt/<node>/summary,
// with the QoS a ROS 2 sensor driver (best effort) and `ros2 topic echo` (reliable) use.
class Robot {
 public:
  // `reliable`: the cloud writer is a ROS 2 default publisher (reliable, keep last 10, blocking
  // as rmw_cyclonedds does, here up to 60 s) instead of a sensor driver's best-effort one.
  Robot(dds_entity_t participant, const std::string& node, bool reliable_input = false) {
    const auto topic = [&](const dds_topic_descriptor_t* type, const std::string& name) {
      const dds_entity_t t = dds_create_topic(
          participant, type, ("rt/" + node + "/" + name).c_str(), nullptr, nullptr);
      EXPECT_GT(t, 0) << dds_strretcode(t);
      return t;
    };
    dds_qos_t* sensor = qos(DDS_RELIABILITY_BEST_EFFORT, 5);
    dds_qos_t* publisher = qos(DDS_RELIABILITY_RELIABLE, 10);
    dds_qset_reliability(publisher, DDS_RELIABILITY_RELIABLE, DDS_SECS(60));
    dds_qos_t* reliable = qos(DDS_RELIABILITY_RELIABLE, 50);
    writer_ = dds_create_writer(participant, topic(&sensor_msgs_msg_dds__PointCloud2__desc, "in"),
                                reliable_input ? publisher : sensor, nullptr);
    clouds_ = dds_create_reader(participant, topic(&sensor_msgs_msg_dds__PointCloud2__desc, "out"),
                                reliable, nullptr);
    summaries_ = dds_create_reader(participant, topic(&std_msgs_msg_dds__String__desc, "summary"),
                                   reliable, nullptr);
    dds_delete_qos(sensor);
    dds_delete_qos(publisher);
    dds_delete_qos(reliable);
  }

  // The node's endpoints matched to ours: the reader of our clouds, the writers of its clouds and
  // summaries (their GUIDs and USER_DATA, as DDS discovery announced them).
  struct Endpoint {
    std::array<std::uint8_t, 16> guid{}, participant{};
    std::string user_data;
  };
  std::vector<Endpoint> node_reader() const { return matched(writer_, true); }
  std::vector<Endpoint> node_writers() const {
    std::vector<Endpoint> out = matched(clouds_, false);
    for (Endpoint& e : matched(summaries_, false)) out.push_back(e);
    return out;
  }
  // Whether the node's reader and writers have matched ours (bounded wait).
  bool connected() const {
    return test::eventually(
        [&] {
          dds_publication_matched_status_t w;
          dds_subscription_matched_status_t c, s;
          return dds_get_publication_matched_status(writer_, &w) == 0 &&
                 dds_get_subscription_matched_status(clouds_, &c) == 0 &&
                 dds_get_subscription_matched_status(summaries_, &s) == 0 && w.current_count > 0 &&
                 c.current_count > 0 && s.current_count > 0;
        },
        60s);
  }
  void publish(const Outgoing& m) const { ASSERT_EQ(dds_write(writer_, &m.message), 0); }

  // Everything that arrived since the last call.
  std::vector<Cloud> take_clouds() {
    std::vector<Cloud> out;
    for (;;) {
      void* sample = nullptr;
      dds_sample_info_t info;
      if (dds_take(clouds_, &sample, &info, 1, 1) <= 0) break;
      const auto& m = *static_cast<const sensor_msgs_msg_dds__PointCloud2_*>(sample);
      if (info.valid_data) {
        Cloud c;
        c.frame_id = m.header.frame_id;
        c.sec = m.header.stamp.sec, c.nanosec = m.header.stamp.nanosec;
        c.height = m.height, c.width = m.width, c.point_step = m.point_step;
        c.row_step = m.row_step;
        for (std::uint32_t k = 0; k < m.fields._length; ++k)
          c.fields.emplace_back(m.fields._buffer[k].name, m.fields._buffer[k].offset);
        c.data.assign(m.data._buffer, m.data._buffer + m.data._length);
        out.push_back(std::move(c));
      }
      dds_return_loan(clouds_, &sample, 1);
    }
    return out;
  }
  std::vector<std::string> take_summaries() {
    std::vector<std::string> out;
    for (;;) {
      void* sample = nullptr;
      dds_sample_info_t info;
      if (dds_take(summaries_, &sample, &info, 1, 1) <= 0) break;
      if (info.valid_data)
        out.push_back(static_cast<const std_msgs_msg_dds__String_*>(sample)->data);
      dds_return_loan(summaries_, &sample, 1);
    }
    return out;
  }
  // Waits (bounded) for the first cloud and summary.
  bool receive(Cloud& cloud, std::string& summary, std::chrono::milliseconds timeout) {
    std::vector<Cloud> clouds;
    std::vector<std::string> summaries;
    test::eventually(
        [&] {
          for (Cloud& c : take_clouds()) clouds.push_back(std::move(c));
          for (std::string& s : take_summaries()) summaries.push_back(std::move(s));
          return !clouds.empty() && !summaries.empty();
        },
        timeout);
    if (clouds.empty() || summaries.empty()) return false;
    cloud = clouds.back(), summary = summaries.back();
    return true;
  }

 private:
  static std::vector<Endpoint> matched(dds_entity_t entity, bool subscriptions) {
    dds_instance_handle_t handles[8];
    const dds_return_t n = subscriptions ? dds_get_matched_subscriptions(entity, handles, 8)
                                         : dds_get_matched_publications(entity, handles, 8);
    std::vector<Endpoint> out;
    for (dds_return_t k = 0; k < n; ++k) {
      dds_builtintopic_endpoint_t* data =
          subscriptions ? dds_get_matched_subscription_data(entity, handles[k])
                        : dds_get_matched_publication_data(entity, handles[k]);
      if (!data) continue;
      Endpoint e;
      std::memcpy(e.guid.data(), data->key.v, 16);
      std::memcpy(e.participant.data(), data->participant_key.v, 16);
      void* user_data = nullptr;
      size_t size = 0;
      if (dds_qget_userdata(data->qos, &user_data, &size) && user_data) {
        e.user_data.assign(static_cast<const char*>(user_data), size);
        dds_free(user_data);
      }
      dds_builtintopic_free_endpoint(data);
      out.push_back(e);
    }
    return out;
  }

  dds_entity_t writer_ = 0, clouds_ = 0, summaries_ = 0;
};

// ROS 2's graph as `ros2 node list` reads it: every ParticipantEntitiesInfo on
// ros_discovery_info (reliable, transient local: what was published before we joined too).
class RosGraph {
 public:
  explicit RosGraph(dds_entity_t participant) {
    topic_ = dds_create_topic(participant, &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc,
                              "ros_discovery_info", nullptr, nullptr);
    dds_qos_t* q = dds_create_qos();
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
    reader_ = dds_create_reader(participant, topic_, q, nullptr);
    dds_delete_qos(q);
  }
  ~RosGraph() {
    dds_delete(reader_);
    dds_delete(topic_);
  }
  struct Node {
    std::array<std::uint8_t, 16> participant{};
    std::string node_namespace, name;
    std::vector<std::array<std::uint8_t, 16>> readers, writers;
  };
  // The newest entry naming `name` in `node_namespace`, waiting for it (bounded).
  std::optional<Node> find(const std::string& node_namespace, const std::string& name,
                           std::chrono::milliseconds timeout) {
    std::optional<Node> found;
    test::eventually(
        [&] {
          for (;;) {
            void* sample = nullptr;
            dds_sample_info_t info;
            if (dds_take(reader_, &sample, &info, 1, 1) <= 0) break;
            const auto& m =
                *static_cast<const rmw_dds_common_msg_dds__ParticipantEntitiesInfo_*>(sample);
            for (std::uint32_t k = 0; info.valid_data && k < m.node_entities_info_seq._length;
                 ++k) {
              const auto& n = m.node_entities_info_seq._buffer[k];
              if (n.node_namespace != node_namespace || n.node_name != name) continue;
              Node node;
              std::memcpy(node.participant.data(), m.gid.data, 16);
              node.node_namespace = n.node_namespace;
              node.name = n.node_name;
              for (std::uint32_t r = 0; r < n.reader_gid_seq._length; ++r)
                node.readers.push_back(gid(n.reader_gid_seq._buffer[r]));
              for (std::uint32_t w = 0; w < n.writer_gid_seq._length; ++w)
                node.writers.push_back(gid(n.writer_gid_seq._buffer[w]));
              found = node;
            }
            dds_return_loan(reader_, &sample, 1);
          }
          return found.has_value();
        },
        timeout);
    return found;
  }

 private:
  static std::array<std::uint8_t, 16> gid(const rmw_dds_common_msg_dds__Gid_& g) {
    std::array<std::uint8_t, 16> out;
    std::memcpy(out.data(), g.data, 16);
    return out;
  }
  dds_entity_t topic_ = 0, reader_ = 0;
};

// Publishes `cloud` until a labeled cloud comes back, as a camera publishes continuously: the
// robot sees the match before the node's reader has matched the robot's writer, and a sample
// written in between is lost.
bool publish_until_labeled(Robot& robot, const PointCloud& cloud, Cloud& got,
                           std::string& summary) {
  for (int attempt = 0; attempt < 30; ++attempt) {
    robot.publish(*outgoing(cloud, "camera", 1000 + attempt, 0));
    if (robot.receive(got, summary, 5s)) return true;
  }
  return false;
}

// The RIHS01 hashes Iron and Jazzy announce for these types.
constexpr const char* kPointCloud2Hash =
    "typehash=RIHS01_9198cabf7da3796ae6fe19c4cb3bdd3525492988c70522628af5daa124bae2b5;";
constexpr const char* kStringHash =
    "typehash=RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18;";

// The node named `name` in `node_namespace` is in ROS 2's graph with the endpoints `robot` is
// matched to, and those endpoints carry ROS 2's type hashes.
void expect_in_the_ros_graph(dds_entity_t participant, const Robot& robot,
                             const std::string& node_namespace, const std::string& name,
                             const Process& node) {
  RosGraph graph(participant);
  const auto found = graph.find(node_namespace, name, 30s);
  ASSERT_TRUE(found) << node_namespace << " " << name << " not on ros_discovery_info\n"
                     << node.log();
  const auto reader = robot.node_reader();
  const auto writers = robot.node_writers();
  ASSERT_EQ(reader.size(), 1u);
  ASSERT_EQ(writers.size(), 2u);
  EXPECT_EQ(found->participant, reader[0].participant);
  const std::vector<std::array<std::uint8_t, 16>> readers{reader[0].guid};
  EXPECT_EQ(found->readers, readers);
  ASSERT_EQ(found->writers.size(), 2u);
  for (const auto& w : writers)
    EXPECT_NE(std::find(found->writers.begin(), found->writers.end(), w.guid),
              found->writers.end());
  EXPECT_EQ(reader[0].user_data, kPointCloud2Hash);
  std::vector<std::string> writer_hashes{writers[0].user_data, writers[1].user_data};
  std::sort(writer_hashes.begin(), writer_hashes.end());
  std::vector<std::string> expected{kPointCloud2Hash, kStringHash};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(writer_hashes, expected);
}

class Ros2Node : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    fs::create_directories(dir_->file("models/random/1"));
    save_model(dir_->file("models/random/1/model.plm"), testing::random_label_model("random"));
    // Loopback only, no multicast: discovery by unicast to 127.0.0.1, so the test neither
    // leaves this machine nor meets another run (a domain of its own as well). A Kinect frame is
    // ~5 MB a sample: a receive buffer of up to 4 MB (the kernel may give less) and 64 kB
    // datagrams, as a robot's CYCLONEDDS_URI has them for point clouds (client/ros2/README.md).
    std::ofstream(dir_->file("cyclonedds.xml"))
        << "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
           "address=\"127.0.0.1\"/></Interfaces><AllowMulticast>false</AllowMulticast>"
           "<MaxMessageSize>65500B</MaxMessageSize></General><Internal>"
           "<SocketReceiveBufferSize min=\"default\" max=\"4MB\"/></Internal><Discovery>"
           "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>50"
           "</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
           "</Domain></CycloneDDS>";
    setenv("CYCLONEDDS_URI", ("file://" + dir_->file("cyclonedds.xml")).c_str(), 1);
    domain_ = 1 + static_cast<std::uint32_t>(::getpid()) % 200;
    unsetenv("ROS_DOMAIN_ID");
    // Iron's and later's graph (16-byte GIDs, type hashes), whatever this shell sourced.
    unsetenv("ROS_DISTRO");
    unsetenv("ROS_LOCALHOST_ONLY");
    unsetenv("ROS_AUTOMATIC_DISCOVERY_RANGE");
    unsetenv("ROS_STATIC_PEERS");
    participant_ = dds_create_participant(domain_, nullptr, nullptr);
    server_ = start_server("127.0.0.1:0", "server.log");
    const auto line = server_->wait_for_log("event=listening ([^\n]*)", 60s);
    std::smatch m;
    if (line && std::regex_search(*line, m, std::regex(" port=(\\d+)")))
      server_address_ = "127.0.0.1:" + m[1].str();
  }
  static void TearDownTestSuite() {
    delete server_;
    if (participant_ > 0) dds_delete(participant_);
    if (localhost_domain_ > 0) dds_delete(localhost_domain_);
    localhost_domain_ = localhost_participant_ = 0;
    delete dir_;
    server_ = nullptr, dir_ = nullptr, participant_ = 0;
  }
  void SetUp() override {
    ASSERT_GT(participant_, 0) << dds_strretcode(participant_);
    ASSERT_FALSE(server_address_.empty()) << "the server did not start:\n" << server_->log();
  }

  static Process* start_server(const std::string& listen, const std::string& log) {
    return new Process(
        {test::binary("primlabel-server"), "--models", dir_->file("models"), "--listen", listen,
         "--metrics-listen", "127.0.0.1:0", "--reload-seconds", "0"},
        dir_->file(log));
  }

  // The command line of primlabel-ros2 named `node` in namespace /`ns` (topics /<ns>/in,
  // /<ns>/out, /<ns>/summary) on `domain`, labeling with `server`, in ROS 2's style; `extra`
  // follows.
  static std::vector<std::string> node_command(const std::string& node, const std::string& ns,
                                               std::uint32_t domain, const std::string& server,
                                               const std::vector<std::string>& extra) {
    std::vector<std::string> args{test::binary("primlabel-ros2"),
                                  "--ros-args",
                                  "-r",
                                  "__node:=" + node,
                                  "-r",
                                  "__ns:=/" + ns,
                                  "-p",
                                  "input_topic:=in",
                                  "-p",
                                  "output_topic:=out",
                                  "-p",
                                  "summary_topic:=summary",
                                  "-p",
                                  "domain_id:=" + std::to_string(domain),
                                  "-p",
                                  "server:=" + server,
                                  "-p",
                                  "deadline:=120"};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  }

  // primlabel-ros2 named `name` in namespace /`name`, with probabilities.
  static std::unique_ptr<Process> start_node(const std::string& name, const std::string& server,
                                             const std::vector<std::string>& extra = {}) {
    std::vector<std::string> flags{"-p", "voxel_size:=" + std::to_string(kVoxel), "-p",
                                   "probabilities:=true"};
    flags.insert(flags.end(), extra.begin(), extra.end());
    return std::make_unique<Process>(node_command(name, name, domain_, server, flags),
                                     dir_->file(name + ".log"));
  }

  // A participant of a robot whose ROS 2 runs with ROS_LOCALHOST_ONLY=1: rmw_cyclonedds then
  // binds Cyclone DDS to 127.0.0.1 (and nothing else: Cyclone's default buffers and datagrams).
  static dds_entity_t localhost_participant() {
    if (localhost_participant_ > 0) return localhost_participant_;
    const dds_domainid_t id = domain_ + 1;
    localhost_domain_ =
        dds_create_domain(id,
                          "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
                          "address=\"127.0.0.1\"/></Interfaces></General></Domain></CycloneDDS>");
    if (localhost_domain_ > 0)
      localhost_participant_ = dds_create_participant(id, nullptr, nullptr);
    return localhost_participant_;
  }

  // primlabel-ros2 as a ROS 2 robot with ROS_LOCALHOST_ONLY=1 and no CYCLONEDDS_URI starts it.
  static std::unique_ptr<Process> start_localhost_only_node(std::vector<std::string> args,
                                                            const std::string& log) {
    const std::string uri = std::getenv("CYCLONEDDS_URI") ? std::getenv("CYCLONEDDS_URI") : "";
    unsetenv("CYCLONEDDS_URI");
    setenv("ROS_LOCALHOST_ONLY", "1", 1);
    auto node = std::make_unique<Process>(args, dir_->file(log));
    unsetenv("ROS_LOCALHOST_ONLY");
    setenv("CYCLONEDDS_URI", uri.c_str(), 1);
    return node;
  }

  static inline test::TempDir* dir_ = nullptr;
  static inline dds_entity_t localhost_domain_ = 0, localhost_participant_ = 0;
  static inline Process* server_ = nullptr;
  static inline std::string server_address_;
  static inline std::uint32_t domain_ = 0;
  static inline dds_entity_t participant_ = 0;
};

PointCloud bunny() { return read_cloud(test::shared_data("pcl/bun0.pcd")); }

// Sends `pcd` as a PointCloud2 to a node and checks what comes back against `primlabel label` on
// the same file: every label and probability, the input's bytes, the echoed frame and stamp, the
// summary.
void expect_labeled_like_the_cli(Robot& robot, const Process& node, const std::string& pcd,
                                 const std::string& server, const std::string& cli_out,
                                 std::int32_t sec) {
  const PointCloud cloud = read_cloud(pcd);
  const auto sent = outgoing(cloud, "camera", sec, 123'456'789);
  Cloud got;
  std::string summary;
  // Sent again every 10 s until it comes back labeled (publish_until_labeled's race: a sample
  // written before the node's reader matches the robot's writer is lost; under load that window
  // outlasted the first sample).
  bool came_back = false;
  for (int attempt = 0; attempt < 18 && !came_back; ++attempt) {
    robot.publish(*sent);
    came_back = robot.receive(got, summary, 10s);
  }
  ASSERT_TRUE(came_back) << node.log();

  const auto r = test::run_command("timeout 180 " + test::binary("primlabel") + " --server " +
                                   server + " --deadline 120 -q label " + pcd + " -o " + cli_out +
                                   " --model random --voxel-size " + std::to_string(kVoxel) +
                                   " --probabilities");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PointCloud cli = read_cloud(cli_out);

  EXPECT_EQ(got.frame_id, "camera");
  EXPECT_EQ(got.sec, sec);
  EXPECT_EQ(got.nanosec, 123'456'789u);
  ASSERT_EQ(got.width, sent->message.width);
  ASSERT_EQ(got.height, sent->message.height);
  ASSERT_EQ(cli.labels.size(), cloud.size());
  std::size_t labels_differ = 0, bytes_differ = 0, probabilities_differ = 0, probabilities = 0,
              labeled = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto label = got.value<std::uint32_t>(i, "label");
    labels_differ += label != cli.labels[i];
    labeled += label != 0;
    bytes_differ +=
        std::memcmp(got.data.data() + i * got.point_step, sent->data.data() + 16 * i, 16) != 0;
  }
  for (const auto& [name, offset] : got.fields) {
    if (name.rfind("prob_", 0) != 0) continue;
    const FloatField* f = cli.find_field(name);
    ASSERT_NE(f, nullptr) << name << " is not in the CLI's file";
    ++probabilities;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const float a = got.value<float>(i, name), b = f->values[i];
      probabilities_differ += !(a == b || (std::isnan(a) && std::isnan(b)));
    }
  }
  EXPECT_EQ(labels_differ, 0u);
  EXPECT_EQ(bytes_differ, 0u);  // the input's x y z and padding, as sent
  EXPECT_EQ(probabilities_differ, 0u);
  EXPECT_GE(probabilities, 2u);
  EXPECT_GT(labeled, count_finite(cloud) / 2);  // not a cloud of zeros
  const auto json = nlohmann::json::parse(summary);
  EXPECT_EQ(json.at("frame_id"), "camera");
  EXPECT_EQ(json.at("stamp_ns"), std::to_string(sec) + "123456789");
  EXPECT_EQ(json.at("model"), "random");
  EXPECT_EQ(json.at("points_received"), std::to_string(cloud.size()));
}

TEST_F(Ros2Node, LabelsLikeTheCli) {
  ASSERT_TRUE(fs::exists(test::shared_data("pcl/bun0.pcd")));
  auto node = start_node("labeler", server_address_);
  Robot robot(participant_, "labeler");
  ASSERT_TRUE(robot.connected()) << node->log();
  {
    SCOPED_TRACE("bun0");
    expect_labeled_like_the_cli(robot, *node, test::shared_data("pcl/bun0.pcd"), server_address_,
                                dir_->file("cli_bun0.pcd"), 1'700'000'000);
  }
  // A whole Kinect frame, organised with its invalid pixels: about 4.9 MB a sample, so DDS
  // fragments it (best effort into the node, reliable out).
  if (fs::exists(test::shared_data("mosd/learn0.pcd"))) {
    SCOPED_TRACE("learn0");
    expect_labeled_like_the_cli(robot, *node, test::shared_data("mosd/learn0.pcd"), server_address_,
                                dir_->file("cli_learn0.pcd"), 1'700'000'001);
  }
  EXPECT_FALSE(node->wait_for(0ms)) << node->log();  // still running
}

TEST_F(Ros2Node, SkipsBadCloudsAndGoesOn) {
  auto node = start_node("bad", server_address_);
  Robot robot(participant_, "bad");
  ASSERT_TRUE(robot.connected()) << node->log();
  const PointCloud cloud = bunny();

  auto no_z = outgoing(cloud, "no_z", 1, 0);
  no_z->message.fields._length = 2;  // x and y only
  auto short_step = outgoing(cloud, "short_step", 2, 0);
  short_step->message.point_step = 8;  // z at offset 8 does not fit
  auto short_data = outgoing(cloud, "short_data", 3, 0);
  short_data->message.data._length /= 2;
  auto empty = outgoing(cloud, "empty", 4, 0);
  empty->message.width = 0;
  for (const Outgoing* bad : {no_z.get(), short_step.get(), short_data.get(), empty.get()}) {
    // One at a time, so the keep-last-1 input does not drop one before it is read; sent again
    // every 5 s until the node names it (a best-effort sample written before the node's reader
    // has matched the robot's writer is lost).
    const std::string refused = "cloud of frame '" + bad->frame_id + "'";
    bool named = false;
    for (int attempt = 0; attempt < 12 && !named; ++attempt) {
      robot.publish(*bad);
      named = test::eventually(
          [&] {
            const std::string log = node->log();
            for (auto at = log.find(refused); at != std::string::npos;
                 at = log.find(refused, at + 1))
              if (log.substr(at, log.find('\n', at) - at).find("not labeled") != std::string::npos)
                return true;
            return false;
          },
          5s);
    }
    ASSERT_TRUE(named) << refused << " not refused\n" << node->log();
  }
  EXPECT_NE(node->log().find("has no field 'z'"), std::string::npos) << node->log();
  EXPECT_FALSE(node->wait_for(0ms)) << node->log();
  EXPECT_TRUE(robot.take_clouds().empty());  // nothing published for a bad cloud

  robot.publish(*outgoing(cloud, "good", 5, 0));
  Cloud got;
  std::string summary;
  ASSERT_TRUE(robot.receive(got, summary, 180s)) << node->log();
  EXPECT_EQ(got.frame_id, "good");
}

TEST_F(Ros2Node, SurvivesAServerThatIsDownAndLabelsOnceItIsBack) {
  // A port in the range the tests may take, where nothing listens yet.
  const std::string address = "127.0.0.1:" + std::to_string(52200 + ::getpid() % 100);
  auto node = start_node("down", address, {"-p", "retries:=1", "-p", "deadline:=5"});
  Robot robot(participant_, "down");
  ASSERT_TRUE(robot.connected()) << node->log();
  // Sent every 5 s until the node says the server is down: a best-effort sample written before
  // the node's reader has matched the robot's writer is lost.
  bool told_down = false;
  for (int attempt = 0; attempt < 12 && !told_down; ++attempt) {
    robot.publish(*outgoing(bunny(), "while_down", 10, 0));
    told_down =
        test::eventually([&] { return node->log().find("UNAVAILABLE") != std::string::npos; }, 5s);
  }
  ASSERT_TRUE(told_down) << node->log();
  EXPECT_FALSE(node->wait_for(0ms)) << node->log();

  std::unique_ptr<Process> server(start_server(address, "server_back.log"));
  ASSERT_TRUE(server->wait_for_log("event=listening", 60s)) << server->log();
  // Sent until one is labeled: the node labels the clouds that come after the server is back.
  Cloud got;
  std::string summary;
  bool labeled = false;
  // (The client's channel may still be backing off from the failed connection for a while.)
  for (int attempt = 0; attempt < 30 && !labeled; ++attempt) {
    robot.publish(*outgoing(bunny(), "after", 11 + attempt, 0));
    // (A cloud sent while down that the node still held may come back first.)
    labeled = robot.receive(got, summary, 5s) && got.frame_id == "after";
  }
  ASSERT_TRUE(labeled) << node->log();
}

TEST_F(Ros2Node, SurvivesABurstAndLabelsTheNewest) {
  auto node = start_node("burst", server_address_);
  Robot robot(participant_, "burst");
  ASSERT_TRUE(robot.connected()) << node->log();
  const PointCloud cloud = bunny();
  constexpr int kBurst = 20;
  for (int k = 1; k <= kBurst; ++k) robot.publish(*outgoing(cloud, "burst", 100 + k, 0));
  // Best effort may lose any sample, the newest too (before the node's reader has matched the
  // robot's writer, all of them): the newest is sent again every 10 s, with its own stamp, until
  // it comes back labeled.
  const int newest = 100 + kBurst;
  std::vector<Cloud> clouds;
  bool labeled_newest = false;
  for (int attempt = 0; attempt < 18 && !labeled_newest; ++attempt) {
    if (attempt > 0) robot.publish(*outgoing(cloud, "burst", newest, 0));
    labeled_newest = test::eventually(
        [&] {
          for (Cloud& c : robot.take_clouds()) clouds.push_back(std::move(c));
          return !clouds.empty() && clouds.back().sec == newest;
        },
        10s);
  }
  ASSERT_TRUE(labeled_newest) << node->log();
  // The newest's copies count once: what was labeled is in order, none twice.
  while (clouds.size() > 1 && clouds[clouds.size() - 2].sec == newest) clouds.pop_back();
  EXPECT_LE(clouds.size(), std::size_t(kBurst));
  std::printf("burst of %d clouds: %zu labeled\n", kBurst, clouds.size());
  for (std::size_t k = 1; k < clouds.size(); ++k) EXPECT_LT(clouds[k - 1].sec, clouds[k].sec);
  EXPECT_FALSE(node->wait_for(0ms)) << node->log();
}

// As `ros2 launch` starts a node: its parameters in a file (launch_ros writes `/**:` for the
// node's own; here the node's name as the key, and a `/**` entry it must not let win), the
// namespace by remap, no node name (so the default). Labeled, then found in ROS 2's graph.
TEST_F(Ros2Node, StartsFromAParamsFileAndIsInTheRosGraph) {
  const std::string file = dir_->file("params.yaml");
  std::ofstream(file) << "/**:\n  ros__parameters:\n    model: no_such_model\n"
                      << "/fromfile/primlabel_ros2:\n  ros__parameters:\n"
                      << "    server: \"" << server_address_ << "\"\n"
                      << "    model: random\n    input_topic: in\n    output_topic: out\n"
                      << "    summary_topic: summary\n    domain_id: " << domain_ << "\n"
                      << "    deadline: 120.0\n    voxel_size: " << kVoxel << "\n"
                      << "    probabilities: true\n    use_sim_time: false\n";
  Process node({test::binary("primlabel-ros2"), "--ros-args", "-r", "__ns:=/fromfile",
                "--params-file", file, "--log-level", "info"},
               dir_->file("fromfile.log"));
  Robot robot(participant_, "fromfile");
  ASSERT_TRUE(robot.connected()) << node.log();
  Cloud got;
  std::string summary;
  ASSERT_TRUE(publish_until_labeled(robot, bunny(), got, summary)) << node.log();
  EXPECT_EQ(nlohmann::json::parse(summary).at("model"), "random");
  expect_in_the_ros_graph(participant_, robot, "/fromfile", "primlabel_ros2", node);
}

// A robot whose ROS 2 runs with ROS_LOCALHOST_ONLY=1 and no CYCLONEDDS_URI: its nodes use only
// 127.0.0.1, so the node must too (Cyclone DDS's default picks another interface here). Found,
// labeling, and listed under its __node:= name.
TEST_F(Ros2Node, FoundWithRosLocalhostOnlyAndNoCycloneddsUri) {
  const dds_entity_t participant = localhost_participant();
  ASSERT_GT(participant, 0) << dds_strretcode(participant);
  auto node = start_localhost_only_node(
      node_command("local_labeler", "local", domain_ + 1, server_address_, {"-p", "model:=random"}),
      "local.log");
  Robot robot(participant, "local");
  ASSERT_TRUE(robot.connected()) << node->log();
  Cloud got;
  std::string summary;
  ASSERT_TRUE(publish_until_labeled(robot, bunny(), got, summary)) << node->log();
  expect_in_the_ros_graph(participant, robot, "/local", "local_labeler", *node);
}

// A robot that publishes Kinect frames with ROS 2's default (reliable, keep last 10) and asks for
// reliable input with a QoS override: 10 of 10 whole frames come back labeled as the CLI labels
// them, under Cyclone DDS's default buffers (localhost only, as above), where best effort loses
// most frames. Then one frame at a time, the round trip beside the CLI's time for the same frame
// (the best of 5 each, taken in turn), printed.
TEST_F(Ros2Node, LabelsEveryFrameOfAReliablePublisher) {
  const std::string kinect = test::shared_data("mosd/learn0.pcd");
  if (!fs::exists(kinect)) GTEST_SKIP() << "no " << kinect;
  const dds_entity_t participant = localhost_participant();
  ASSERT_GT(participant, 0) << dds_strretcode(participant);
  const std::string file = dir_->file("reliable.yaml");
  std::ofstream(file) << "/**:\n  ros__parameters:\n    qos_overrides:\n      /reliable/in:\n"
                      << "        subscription:\n          reliability: reliable\n"
                      << "          depth: 10\n      /reliable/out:\n        publisher:\n"
                      << "          depth: 10\n";
  auto node = start_localhost_only_node(
      node_command("reliable", "reliable", domain_ + 1, server_address_,
                   {"-p", "model:=random", "-p", "voxel_size:=" + std::to_string(kVoxel),
                    "--params-file", file}),
      "reliable.log");
  Robot robot(participant, "reliable", /*reliable_input=*/true);
  ASSERT_TRUE(robot.connected()) << node->log();
  {  // Both sides matched before the frames that count.
    Cloud warm_up;
    std::string summary;
    ASSERT_TRUE(publish_until_labeled(robot, bunny(), warm_up, summary)) << node->log();
    test::eventually([&] { return robot.take_clouds().empty() && robot.take_summaries().empty(); },
                     2s);
  }

  const std::string cli_out = dir_->file("cli_reliable.pcd");
  // `primlabel label` on the frame; its wall time in seconds.
  const auto cli_label = [&] {
    const auto start = std::chrono::steady_clock::now();
    const auto r =
        test::run_command("timeout 180 " + test::binary("primlabel") + " --server " +
                          server_address_ + " --deadline 120 -q label " + kinect + " -o " +
                          cli_out + " --model random --voxel-size " + std::to_string(kVoxel));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  cli_label();
  const PointCloud cli = read_cloud(cli_out);
  const PointCloud cloud = read_cloud(kinect);

  constexpr int kFrames = 10;
  for (int k = 0; k < kFrames; ++k) robot.publish(*outgoing(cloud, "kinect", 200 + k, 0));
  std::vector<Cloud> clouds;
  test::eventually(
      [&] {
        for (Cloud& c : robot.take_clouds()) clouds.push_back(std::move(c));
        return clouds.size() >= std::size_t(kFrames);
      },
      300s);
  ASSERT_EQ(clouds.size(), std::size_t(kFrames)) << node->log();
  for (int k = 0; k < kFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const Cloud& got = clouds[k];
    EXPECT_EQ(got.sec, 200 + k);  // each once, in order
    ASSERT_EQ(std::size_t(got.width) * got.height, cloud.size());
    ASSERT_EQ(got.data.size(), std::size_t(got.row_step) * got.height);
    std::size_t labels_differ = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i)
      labels_differ += got.value<std::uint32_t>(i, "label") != cli.labels[i];
    EXPECT_EQ(labels_differ, 0u);
  }

  // Then one frame at a time, the node and the CLI in turn so both see the same load on the
  // machine: the best of 5 each, printed. A figure, not a check: under ctest -j2 the other test's
  // load swung it by tens of ms either way (node 259 vs CLI 216 ms in one run, 467 vs 487 in
  // another), and speed is for benchmarks to measure, not for unit tests to time.
  double node_seconds = 1e9, cli_seconds = 1e9;
  for (int run = 0; run < 5; ++run) {
    cli_seconds = std::min(cli_seconds, cli_label());
    robot.take_summaries();
    const auto sent = outgoing(cloud, "kinect", 300 + run, 0);
    const auto start = std::chrono::steady_clock::now();
    robot.publish(*sent);
    Cloud got;
    std::string summary;
    ASSERT_TRUE(robot.receive(got, summary, 180s)) << node->log();
    node_seconds =
        std::min(node_seconds,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    EXPECT_EQ(got.sec, 300 + run);
  }
  std::printf("Kinect frame (learn0), best of 5: node round trip %.1f ms, CLI %.1f ms\n",
              node_seconds * 1e3, cli_seconds * 1e3);
  EXPECT_FALSE(node->wait_for(0ms)) << node->log();
}

TEST_F(Ros2Node, RefusesBadArguments) {
  for (const std::vector<std::string>& bad : {std::vector<std::string>{"-p", "voxel_size:=abc"},
                                              {"-p", "no_such:=1"},
                                              {"-r", "__ns:=robot"},
                                              {"-p", "domain_id:=300"},
                                              {"-p", "objects:=true"},
                                              {"--params-file", "/no/such/params.yaml"},
                                              {"--log-level", "loud"}}) {
    std::vector<std::string> args{test::binary("primlabel-ros2"), "--ros-args"};
    args.insert(args.end(), bad.begin(), bad.end());
    Process p(args, dir_->file("bad_args.log"));
    EXPECT_EQ(p.wait_for(30s), 2) << bad[1] << "\n" << p.log();
  }
}

}  // namespace
}  // namespace primlabel::ros2test
