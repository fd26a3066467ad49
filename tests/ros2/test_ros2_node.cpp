// ros2.LabelsPointCloud2: primlabel-ros2 between Cyclone DDS peers that play the robot and a real
// primlabel-server, all on 127.0.0.1. This process writes sensor_msgs/msg/PointCloud2 samples
// with ROS 2's DDS type and topic names (sensor_msgs::msg::dds_::PointCloud2_ on rt/<name>), on a
// domain of its own with Cyclone DDS held to the loopback interface, and reads the labeled cloud
// and the summary back as a ROS 2 subscriber would. Checks: the labels and probabilities equal
// `primlabel label` on the same file point for point, the input's bytes and the echoed frame and
// stamp; bad clouds are logged and skipped; a server that is down is logged and the node labels
// once it is back; a burst leaves the node alive with the newest cloud labeled. Every wait is
// bounded; every process is killed.

#include <dds/dds.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/model/label_model.hpp"
#include "process.hpp"
#include "random_label_model.hpp"
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
  Robot(dds_entity_t participant, const std::string& node) {
    const auto topic = [&](const dds_topic_descriptor_t* type, const std::string& name) {
      const dds_entity_t t = dds_create_topic(
          participant, type, ("rt/" + node + "/" + name).c_str(), nullptr, nullptr);
      EXPECT_GT(t, 0) << dds_strretcode(t);
      return t;
    };
    dds_qos_t* sensor = qos(DDS_RELIABILITY_BEST_EFFORT, 5);
    dds_qos_t* reliable = qos(DDS_RELIABILITY_RELIABLE, 50);
    writer_ = dds_create_writer(participant, topic(&sensor_msgs_msg_dds__PointCloud2__desc, "in"),
                                sensor, nullptr);
    clouds_ = dds_create_reader(participant, topic(&sensor_msgs_msg_dds__PointCloud2__desc, "out"),
                                reliable, nullptr);
    summaries_ = dds_create_reader(participant, topic(&std_msgs_msg_dds__String__desc, "summary"),
                                   reliable, nullptr);
    dds_delete_qos(sensor);
    dds_delete_qos(reliable);
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
  dds_entity_t writer_ = 0, clouds_ = 0, summaries_ = 0;
};

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

  // primlabel-ros2 named `name` (topics /<name>/in, /<name>/out, /<name>/summary), in ROS 2's
  // command-line style.
  static std::unique_ptr<Process> start_node(const std::string& name, const std::string& server,
                                             std::vector<std::string> extra = {}) {
    std::vector<std::string> args{test::binary("primlabel-ros2"),
                                  "--ros-args",
                                  "-r",
                                  "__node:=" + name,
                                  "-r",
                                  "__ns:=/" + name,
                                  "-p",
                                  "input_topic:=in",
                                  "-p",
                                  "output_topic:=out",
                                  "-p",
                                  "summary_topic:=summary",
                                  "-p",
                                  "domain_id:=" + std::to_string(domain_),
                                  "-p",
                                  "server:=" + server,
                                  "-p",
                                  "deadline:=120",
                                  "-p",
                                  "voxel_size:=" + std::to_string(kVoxel),
                                  "-p",
                                  "probabilities:=true"};
    args.insert(args.end(), extra.begin(), extra.end());
    return std::make_unique<Process>(args, dir_->file(name + ".log"));
  }

  static inline test::TempDir* dir_ = nullptr;
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
  robot.publish(*sent);
  Cloud got;
  std::string summary;
  ASSERT_TRUE(robot.receive(got, summary, 180s)) << node.log();

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
  int expected_errors = 0;
  for (const Outgoing* bad : {no_z.get(), short_step.get(), short_data.get(), empty.get()}) {
    robot.publish(*bad);
    ++expected_errors;
    // One at a time, so the keep-last-1 input does not drop one before it is read.
    ASSERT_TRUE(test::eventually(
        [&] {
          const std::string log = node->log();
          std::size_t count = 0;
          for (auto at = log.find("not labeled"); at != std::string::npos;
               at = log.find("not labeled", at + 1))
            ++count;
          return count >= std::size_t(expected_errors);
        },
        60s))
        << node->log();
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
  robot.publish(*outgoing(bunny(), "while_down", 10, 0));
  ASSERT_TRUE(
      test::eventually([&] { return node->log().find("UNAVAILABLE") != std::string::npos; }, 60s))
      << node->log();
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
    labeled = robot.receive(got, summary, 5s);
  }
  ASSERT_TRUE(labeled) << node->log();
  EXPECT_EQ(got.frame_id, "after");
}

TEST_F(Ros2Node, SurvivesABurstAndLabelsTheNewest) {
  auto node = start_node("burst", server_address_);
  Robot robot(participant_, "burst");
  ASSERT_TRUE(robot.connected()) << node->log();
  const PointCloud cloud = bunny();
  constexpr int kBurst = 20;
  for (int k = 1; k <= kBurst; ++k) robot.publish(*outgoing(cloud, "burst", 100 + k, 0));
  std::vector<Cloud> clouds;
  ASSERT_TRUE(test::eventually(
      [&] {
        for (Cloud& c : robot.take_clouds()) clouds.push_back(std::move(c));
        return !clouds.empty() && clouds.back().sec == 100 + kBurst;
      },
      180s))
      << node->log();
  EXPECT_LE(clouds.size(), std::size_t(kBurst));
  std::printf("burst of %d clouds: %zu labeled\n", kBurst, clouds.size());
  for (std::size_t k = 1; k < clouds.size(); ++k)
    EXPECT_LT(clouds[k - 1].sec, clouds[k].sec);  // in order, none twice
  EXPECT_FALSE(node->wait_for(0ms)) << node->log();
}

TEST_F(Ros2Node, RefusesBadArguments) {
  for (const std::vector<std::string>& bad : {std::vector<std::string>{"-p", "voxel_size:=abc"},
                                              {"-p", "no_such:=1"},
                                              {"-r", "__ns:=robot"},
                                              {"-p", "domain_id:=300"},
                                              {"-p", "objects:=true"}}) {
    std::vector<std::string> args{test::binary("primlabel-ros2"), "--ros-args"};
    args.insert(args.end(), bad.begin(), bad.end());
    Process p(args, dir_->file("bad_args.log"));
    EXPECT_EQ(p.wait_for(30s), 2) << bad[1] << "\n" << p.log();
  }
}

}  // namespace
}  // namespace primlabel::ros2test
