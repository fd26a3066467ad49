// ros.LabelsPointCloud2: primlabel-ros between a real rosmaster and a real primlabel-server, all
// on 127.0.0.1 with free ports (ROS_HOME and ROS_LOG_DIR in a temporary directory). This process
// publishes PCDs as PointCloud2 (a crop of a real mOSD Kinect frame, organised with its invalid
// pixels, and bun0 with FLOAT64 coordinates) and checks the labeled clouds point for point
// against `primlabel label` on the same files: labels, probabilities and confidence, width and
// height, every input field and byte kept, frame_id and stamp echoed through the service. Then
// that the node survives an unreadable cloud and a failing request, keeps only the newest cloud
// of a burst, and refuses bad parameters. Every wait is bounded; every process is killed.

#include <netinet/in.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <sys/socket.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>

#include "pointcloud2_test_util.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "process.hpp"
#include "random_model_file.hpp"
#include "test_util.hpp"

namespace primlabel::rostest {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::Process;

constexpr float kVoxel = 0.005f;  // the node's ~voxel_size and the CLI's --voxel-size

// A free TCP port on 127.0.0.1 (bound, read, released: rosmaster takes it right after).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof address;
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size) != 0)
    throw std::runtime_error("no free port");
  const int port = ntohs(address.sin_port);
  ::close(fd);
  return port;
}

// What arrives on one topic, kept for the test thread.
template <class Message>
class Inbox {
 public:
  Inbox(ros::NodeHandle& node, const std::string& topic)
      : subscriber_(node.subscribe(topic, 20, &Inbox::receive, this)) {}
  void receive(const boost::shared_ptr<const Message>& message) {
    std::lock_guard lock(mutex_);
    messages_.push_back(*message);
  }
  std::size_t size() const {
    std::lock_guard lock(mutex_);
    return messages_.size();
  }
  std::vector<Message> messages() const {
    std::lock_guard lock(mutex_);
    return messages_;
  }
  const ros::Subscriber& subscriber() const { return subscriber_; }

 private:
  ros::Subscriber subscriber_;
  mutable std::mutex mutex_;
  std::vector<Message> messages_;
};

// One primlabel-ros with its own name and topics /<name>/in, /<name>/out, /<name>/summary.
struct NodeUnderTest {
  NodeUnderTest(const std::string& name, const std::vector<std::string>& parameters,
                const std::string& log)
      : name(name), process(arguments(name, parameters), log) {}
  static std::vector<std::string> arguments(const std::string& name,
                                            const std::vector<std::string>& parameters) {
    std::vector<std::string> args{
        test::binary("primlabel-ros"), "__name:=" + name, "_input_topic:=/" + name + "/in",
        "_output_topic:=/" + name + "/out", "_summary_topic:=/" + name + "/summary"};
    args.insert(args.end(), parameters.begin(), parameters.end());
    return args;
  }
  std::string name;
  Process process;
};

class RosNode : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!fs::exists(test::binary("primlabel-server")) || !fs::exists(PRIMLABEL_ROSMASTER)) return;
    dir_ = new test::TempDir();
    fs::create_directories(dir_->file("models/random/1"));
    write_random_label_model(dir_->file("models/random/1/model.plm"), "random");
    fs::create_directories(dir_->file("ros"));
    setenv("ROS_HOME", dir_->file("ros").c_str(), 1);
    setenv("ROS_LOG_DIR", dir_->file("ros/log").c_str(), 1);
    setenv("ROS_IP", "127.0.0.1", 1);
    unsetenv("ROS_HOSTNAME");
    const std::string master_uri = "http://127.0.0.1:" + std::to_string(free_port());
    setenv("ROS_MASTER_URI", master_uri.c_str(), 1);
    master_ = new Process(
        {PRIMLABEL_ROSMASTER, "--core", "-p", master_uri.substr(master_uri.rfind(':') + 1)},
        dir_->file("rosmaster.log"));
    server_ =
        new Process({test::binary("primlabel-server"), "--models", dir_->file("models"), "--listen",
                     "127.0.0.1:0", "--metrics-listen", "127.0.0.1:0", "--reload-seconds", "0"},
                    dir_->file("server.log"));
    const auto line = server_->wait_for_log("event=listening ([^\n]*)", 60s);
    std::smatch m;
    if (line && std::regex_search(*line, m, std::regex(" port=(\\d+)")))
      server_address_ = "127.0.0.1:" + m[1].str();
    ros::init(ros::M_string{{"__master", master_uri}, {"__ip", "127.0.0.1"}}, "primlabel_ros_test",
              ros::init_options::NoSigintHandler | ros::init_options::AnonymousName |
                  ros::init_options::NoRosout);
    master_up_ = test::eventually([] { return ros::master::check(); }, 30s);
    if (!master_up_ || server_address_.empty()) return;
    node_handle_ = new ros::NodeHandle();
    spinner_ = new ros::AsyncSpinner(1);
    spinner_->start();
  }
  static void TearDownTestSuite() {
    delete spinner_;  // stops it
    delete node_handle_;
    if (ros::isInitialized()) ros::shutdown();
    delete server_;  // SIGKILL and reaped
    delete master_;
    delete dir_;
    spinner_ = nullptr, node_handle_ = nullptr, server_ = nullptr, master_ = nullptr;
    dir_ = nullptr;
  }
  void SetUp() override {
    if (!dir_) GTEST_SKIP() << "primlabel-server is not built or rosmaster is not installed";
    ASSERT_TRUE(master_up_) << "rosmaster did not answer:\n" << master_->log();
    ASSERT_FALSE(server_address_.empty()) << "the server did not start:\n" << server_->log();
  }

  static std::string file(const std::string& name) { return dir_->file(name); }

  // A node labeling with the random model through the test's server.
  static std::unique_ptr<NodeUnderTest> start_node(const std::string& name,
                                                   std::vector<std::string> parameters = {}) {
    std::vector<std::string> all{"_server:=" + server_address_, "_deadline:=120",
                                 "_voxel_size:=" + std::to_string(kVoxel)};
    all.insert(all.end(), parameters.begin(), parameters.end());
    return std::make_unique<NodeUnderTest>(name, all, file(name + ".log"));
  }

  // The CLI's labeled version of `pcd` (same model and voxel size as the node), with
  // `options` besides (default: the probabilities).
  static PointCloud cli_labels(const std::string& pcd, const std::string& out,
                               const std::string& options = "--probabilities") {
    const auto r =
        test::run_command("timeout 180 " + test::binary("primlabel") + " --server " +
                          server_address_ + " --deadline 120 -q label " + pcd + " -o " + out +
                          " --model random --voxel-size " + std::to_string(kVoxel) + " " + options);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return read_cloud(out);
  }

  static inline test::TempDir* dir_ = nullptr;
  static inline Process* master_ = nullptr;
  static inline Process* server_ = nullptr;
  static inline bool master_up_ = false;
  static inline std::string server_address_;
  static inline ros::NodeHandle* node_handle_ = nullptr;
  static inline ros::AsyncSpinner* spinner_ = nullptr;
};

// Waits (bounded) until the node subscribes to `publisher` and `inbox` hears from the node.
bool connected(const ros::Publisher& publisher, const ros::Subscriber& inbox) {
  return test::eventually(
      [&] { return publisher.getNumSubscribers() > 0 && inbox.getNumPublishers() > 0; }, 60s);
}

// The organised test cloud: a 240 x 160 crop of a real Kinect frame (its invalid pixels NaN,
// its ground-truth `label` and `rgba` fields kept), as a PCD the CLI reads.
PointCloud mosd_crop(const std::string& out) {
  const PointCloud frame = read_cloud(test::shared_data("mosd/learn0.pcd"));
  PointCloud crop;
  crop.width = 240;
  crop.height = 160;
  const std::uint32_t top = 200, left = 200;
  for (std::uint32_t r = top; r < top + crop.height; ++r)
    for (std::uint32_t c = left; c < left + crop.width; ++c) {
      const std::size_t i = std::size_t(r) * frame.width + c;
      crop.xyz.push_back(frame.xyz[i]);
      crop.labels.push_back(frame.labels[i]);
      crop.rgba.push_back(frame.rgba[i]);
    }
  // Invalid pixels as a depth camera has them, whatever this crop of the frame holds.
  for (std::uint32_t r = 0; r < 10; ++r)
    for (std::uint32_t c = 0; c < 12; ++c)
      crop.xyz[r * crop.width + c].setConstant(std::numeric_limits<float>::quiet_NaN());
  write_pcd(out, crop, PcdEncoding::kBinary);
  return crop;
}

void expect_labeled_like_the_cli(const PointCloud2& sent, const PointCloud2& got,
                                 const PointCloud& cli) {
  ASSERT_EQ(got.width, sent.width);
  ASSERT_EQ(got.height, sent.height);
  EXPECT_EQ(got.header.frame_id, sent.header.frame_id);
  EXPECT_EQ(got.header.stamp, sent.header.stamp);
  EXPECT_EQ(got.is_dense, sent.is_dense);
  const std::size_t n = std::size_t(sent.width) * sent.height;
  ASSERT_EQ(cli.size(), n);
  ASSERT_EQ(cli.labels.size(), n);
  // The CLI's file and the node's message name the per-class fields alike (prob_<class>).
  std::vector<std::string> prob_fields;
  std::vector<const FloatField*> cli_fields;
  for (const PointField& f : got.fields)
    if (f.name.rfind("prob_", 0) == 0) {
      prob_fields.push_back(f.name);
      cli_fields.push_back(cli.find_field(f.name));
      ASSERT_NE(cli_fields.back(), nullptr) << f.name << " is not in the CLI's file";
    }
  ASSERT_GE(prob_fields.size(), 2u);
  for (const PointField& f : sent.fields) {  // the input's layout, the ground truth replaced
    if (f.name == "label") continue;
    const PointField& kept = field_named(got, f.name);
    EXPECT_EQ(kept.offset, f.offset) << f.name;
    EXPECT_EQ(kept.datatype, f.datatype) << f.name;
  }
  // NaN equals NaN here: points without a descriptor have NaN probabilities (and confidence).
  auto same = [](float a, float b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  std::size_t bytes_differ = 0, labels_differ = 0, probabilities_differ = 0, confidence_differs = 0,
              labeled = 0;
  for (std::size_t i = 0; i < n; ++i) {
    bytes_differ += std::memcmp(point_bytes(got, i), point_bytes(sent, i), sent.point_step) != 0;
    const std::uint32_t label = value_of<std::uint32_t>(got, i, "label");
    labels_differ += label != cli.labels[i];
    labeled += label != 0;
    float best = std::numeric_limits<float>::quiet_NaN();
    for (std::size_t k = 0; k < prob_fields.size(); ++k) {
      const float p = value_of<float>(got, i, prob_fields[k]);
      probabilities_differ += !same(p, cli_fields[k]->values[i]);
      if (!std::isnan(p) && !(p <= best)) best = p;
    }
    confidence_differs += !same(value_of<float>(got, i, "confidence"), best);
  }
  EXPECT_EQ(bytes_differ, 0u);
  EXPECT_EQ(labels_differ, 0u);
  EXPECT_EQ(probabilities_differ, 0u);
  EXPECT_EQ(confidence_differs, 0u);
  EXPECT_GT(labeled, n / 2);  // not a cloud of zeros
}

TEST_F(RosNode, LabelsPointCloud2LikeTheCli) {
  auto node = start_node("labeler", {"_probabilities:=true", "_confidence:=true"});
  ros::Publisher publisher = node_handle_->advertise<PointCloud2>("/labeler/in", 4);
  Inbox<PointCloud2> clouds(*node_handle_, "/labeler/out");
  Inbox<std_msgs::String> summaries(*node_handle_, "/labeler/summary");
  ASSERT_TRUE(connected(publisher, clouds.subscriber())) << node->process.log();
  ASSERT_TRUE(test::eventually([&] { return summaries.subscriber().getNumPublishers() > 0; }, 60s));

  struct Case {
    std::string pcd;
    PointCloud cloud;
    MessageLayout layout;
    std::string frame;
  };
  std::vector<Case> cases;
  if (fs::exists(test::shared_data("mosd/learn0.pcd")))
    cases.push_back({file("mosd_crop.pcd"), mosd_crop(file("mosd_crop.pcd")),
                     layout_of(false, false, 16), "camera_depth_optical_frame"});
  ASSERT_TRUE(fs::exists(test::shared_data("pcl/bun0.pcd")));
  cases.push_back({test::shared_data("pcl/bun0.pcd"), read_cloud(test::shared_data("pcl/bun0.pcd")),
                   layout_of(true, false, 0), "bunny"});
  std::uint32_t seconds = 1'700'000'000;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.pcd);
    PointCloud2 sent = to_pointcloud2(c.cloud, c.layout);
    sent.header.frame_id = c.frame;
    sent.header.stamp = ros::Time(++seconds, 123'456'789);
    const std::size_t before = clouds.size();
    publisher.publish(sent);
    ASSERT_TRUE(test::eventually([&] { return clouds.size() > before; }, 180s))
        << node->process.log();
    const PointCloud2 got = clouds.messages().back();
    const PointCloud cli = cli_labels(c.pcd, file("cli_" + fs::path(c.pcd).filename().string()));
    expect_labeled_like_the_cli(sent, got, cli);
    // The summary: the service's echo of the frame and stamp, the model, every point.
    ASSERT_TRUE(test::eventually([&] { return summaries.size() > before; }, 30s));
    const auto json = nlohmann::json::parse(summaries.messages().back().data);
    EXPECT_EQ(json.at("frame_id"), c.frame);
    EXPECT_EQ(json.at("stamp_ns"), std::to_string(sent.header.stamp.toNSec()));
    EXPECT_EQ(json.at("model"), "random");
    EXPECT_EQ(json.at("points_received"), std::to_string(c.cloud.size()));
  }
  EXPECT_FALSE(node->process.wait_for(0ms)) << node->process.log();  // still running
}

// A robot's one call for objects and primitives: the table-top objects as a uint32 `object` per
// point and the fitted instances as a uint32 `segment`, both described in the summary, the same
// as `primlabel label --tabletop --objects --primitives` on the same file.
TEST_F(RosNode, PublishesObjectsAndPrimitivesLikeTheCli) {
  if (!fs::exists(test::shared_data("mosd/learn0.pcd"))) GTEST_SKIP() << "no mOSD learn0";
  auto node =
      start_node("objects", {"_tabletop_only:=true", "_objects:=true", "_primitives:=true"});
  ros::Publisher publisher = node_handle_->advertise<PointCloud2>("/objects/in", 4);
  Inbox<PointCloud2> clouds(*node_handle_, "/objects/out");
  Inbox<std_msgs::String> summaries(*node_handle_, "/objects/summary");
  ASSERT_TRUE(connected(publisher, clouds.subscriber())) << node->process.log();
  ASSERT_TRUE(test::eventually([&] { return summaries.subscriber().getNumPublishers() > 0; }, 60s));

  // The whole frame: the table-top stage needs the table around the objects.
  const std::string pcd = test::shared_data("mosd/learn0.pcd");
  const PointCloud frame = read_cloud(pcd);
  PointCloud2 sent = to_pointcloud2(frame, layout_of(false, false, 0));
  sent.header.frame_id = "camera_depth_optical_frame";
  sent.header.stamp = ros::Time(1'700'000'100, 5);
  publisher.publish(sent);
  ASSERT_TRUE(test::eventually([&] { return clouds.size() == 1 && summaries.size() == 1; }, 180s))
      << node->process.log();
  const PointCloud2 got = clouds.messages().back();
  const auto summary = nlohmann::json::parse(summaries.messages().back().data);
  const PointCloud cli = cli_labels(pcd, file("cli_objects.pcd"),
                                    "--tabletop --objects " + file("cli_objects.json") +
                                        " --primitives " + file("cli_primitives.json"));
  const FloatField* cli_object = cli.find_field("object");
  ASSERT_NE(cli_object, nullptr);
  std::ifstream objects_file(file("cli_objects.json"));
  const auto cli_objects = nlohmann::json::parse(objects_file);

  const std::size_t n = frame.size();
  ASSERT_EQ(std::size_t(got.width) * got.height, n);
  ASSERT_EQ(cli.size(), n);
  const auto& objects = summary.at("objects");
  const auto& primitives = summary.at("primitives");
  ASSERT_GE(objects.size(), 1u) << "no object on learn0's table";
  EXPECT_EQ(objects.size(), cli_objects.at("objects").size());
  ASSERT_GE(primitives.size(), 1u);
  std::size_t labels_differ = 0, objects_differ = 0, bad_segments = 0, on_table = 0, on_objects = 0,
              in_segments = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t label = value_of<std::uint32_t>(got, i, "label");
    const std::uint32_t object = value_of<std::uint32_t>(got, i, "object");
    const std::uint32_t segment = value_of<std::uint32_t>(got, i, "segment");
    labels_differ += label != cli.labels[i];
    const float cli_id = cli_object->row(i)[0];
    objects_differ += cli_id < 0 ? object != 0xFFFFFFFFu : object != std::uint32_t(cli_id);
    on_table += object == 0;
    on_objects += object != 0 && object != 0xFFFFFFFFu;
    EXPECT_TRUE(object == 0xFFFFFFFFu || object <= objects.size()) << i;
    if (segment == 0xFFFFFFFFu) continue;
    ++in_segments;
    // A segment's points are of its class.
    bad_segments +=
        segment >= primitives.size() || primitives[segment].value("class_id", 0u) != label;
  }
  EXPECT_EQ(labels_differ, 0u);
  EXPECT_EQ(objects_differ, 0u);
  EXPECT_EQ(bad_segments, 0u);
  EXPECT_GT(on_table, n / 10);
  EXPECT_GT(on_objects, 1000u);
  EXPECT_GT(in_segments, 1000u);
  EXPECT_TRUE(summary.contains("table"));
  EXPECT_FALSE(node->process.wait_for(0ms)) << node->process.log();
}

TEST_F(RosNode, KeepsRunningAfterAnUnreadableCloudAndAFailedRequest) {
  auto node = start_node("survivor");
  auto lost = start_node("lost", {"_model:=no-such-model"});
  ros::Publisher publisher = node_handle_->advertise<PointCloud2>("/survivor/in", 4);
  ros::Publisher lost_publisher = node_handle_->advertise<PointCloud2>("/lost/in", 4);
  Inbox<PointCloud2> clouds(*node_handle_, "/survivor/out");
  Inbox<PointCloud2> lost_clouds(*node_handle_, "/lost/out");
  ASSERT_TRUE(connected(publisher, clouds.subscriber())) << node->process.log();
  ASSERT_TRUE(connected(lost_publisher, lost_clouds.subscriber())) << lost->process.log();

  const PointCloud bunny = read_cloud(test::shared_data("pcl/bun0.pcd"));
  PointCloud2 unreadable = to_pointcloud2(bunny);
  unreadable.fields[2].datatype = PointField::UINT8;
  publisher.publish(unreadable);
  ASSERT_TRUE(node->process.wait_for_log("not labeled: field 'z' has datatype 2", 60s))
      << node->process.log();
  PointCloud2 good = to_pointcloud2(bunny);
  good.header.frame_id = "after_the_error";
  publisher.publish(good);
  ASSERT_TRUE(test::eventually([&] { return clouds.size() == 1; }, 120s)) << node->process.log();
  EXPECT_EQ(clouds.messages()[0].header.frame_id, "after_the_error");
  EXPECT_NE(node->process.log().find("ERROR"), std::string::npos);  // ROS_ERROR's level

  lost_publisher.publish(good);
  ASSERT_TRUE(lost->process.wait_for_log("not labeled: NOT_FOUND", 120s)) << lost->process.log();
  EXPECT_FALSE(lost->process.wait_for(500ms)) << lost->process.log();
  EXPECT_EQ(lost_clouds.size(), 0u);
  EXPECT_FALSE(node->process.wait_for(0ms));
}

// Queue size 1, drop-oldest: a burst faster than the server is labeled up to its newest cloud,
// in order, without a backlog of every cloud.
TEST_F(RosNode, ABurstIsLabeledUpToItsNewestCloud) {
  auto node = start_node("burst");
  ros::Publisher publisher = node_handle_->advertise<PointCloud2>("/burst/in", 20);
  Inbox<PointCloud2> clouds(*node_handle_, "/burst/out");
  ASSERT_TRUE(connected(publisher, clouds.subscriber())) << node->process.log();
  PointCloud2 cloud = to_pointcloud2(read_cloud(test::shared_data("pcl/bun0.pcd")));
  constexpr int kBurst = 8;
  for (int i = 1; i <= kBurst; ++i) {
    cloud.header.stamp = ros::Time(100 + i, 0);
    publisher.publish(cloud);
  }
  ASSERT_TRUE(test::eventually(
      [&] {
        const auto got = clouds.messages();
        return !got.empty() && got.back().header.stamp == ros::Time(100 + kBurst, 0);
      },
      120s))
      << node->process.log();
  const auto got = clouds.messages();
  EXPECT_LE(got.size(), std::size_t(kBurst));
  for (std::size_t i = 1; i < got.size(); ++i)
    EXPECT_LT(got[i - 1].header.stamp, got[i].header.stamp);
  std::printf("burst of %d clouds: %zu labeled\n", kBurst, got.size());
}

TEST_F(RosNode, RefusesBadParametersAtStart) {
  int run = 0;
  for (const std::string& bad :
       {"_voxel_size:=-1", "_deadline:=0", "_server:=host:port", "_probabilities:=maybe",
        "_viewpoint:=[1.0,2.0]", "_viewpoint:=up", "_objects:=true"}) {
    // A name of its own each time: private parameters stay on the master after the node exits.
    auto node = start_node("bad" + std::to_string(++run), {bad});
    const auto code = node->process.wait_for(60s);
    ASSERT_TRUE(code.has_value()) << bad << "\n" << node->process.log();
    EXPECT_EQ(*code, 2) << bad << "\n" << node->process.log();
    const std::string key = bad.substr(1, bad.find(':') - 1);
    EXPECT_NE(node->process.log().find("~" + key), std::string::npos) << node->process.log();
  }
}

}  // namespace
}  // namespace primlabel::rostest
