// primlabel-ros2's command line and names without DDS: ROS 2's -p/-r arguments, the namespace
// and remaps, the topic names as rmw_cyclonedds has them on DDS (rt/...), parameters files,
// --log-level, use_sim_time, QoS overrides, the discovery variables as Cyclone DDS configuration,
// and what is refused.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "primlabel/ros2/ros2_arguments.hpp"
#include "primlabel/ros2/ros2_discovery.hpp"
#include "primlabel/ros2/ros2_names.hpp"
#include "primlabel/ros2/ros2_params_file.hpp"

namespace primlabel::ros2node {
namespace {

TEST(Ros2Names, ResolveInTheNamespaceAndPrefixRt) {
  EXPECT_EQ(resolve_topic("points", "/", "n"), "/points");
  EXPECT_EQ(resolve_topic("points", "/robot", "n"), "/robot/points");
  EXPECT_EQ(resolve_topic("/camera/points", "/robot", "n"), "/camera/points");
  EXPECT_EQ(resolve_topic("~/out", "/robot", "labeler"), "/robot/labeler/out");
  EXPECT_EQ(dds_topic_name("/robot/points"), "rt/robot/points");
  EXPECT_THROW(resolve_topic("a//b", "/", "n"), std::invalid_argument);
  EXPECT_THROW(resolve_topic("1points", "/", "n"), std::invalid_argument);
  EXPECT_THROW(resolve_topic("points/", "/", "n"), std::invalid_argument);
  EXPECT_THROW(check_namespace("robot"), std::invalid_argument);
  EXPECT_NO_THROW(check_namespace("/robot/arm_1"));
}

TEST(Ros2Arguments, ParametersRemapsNamespaceAndDomain) {
  unsetenv("ROS_DOMAIN_ID");
  const Ros2Settings s = parse_arguments({"--ros-args",
                                          "-p",
                                          "server:=labeler",
                                          "-p",
                                          "model:='tabletop-kinect'",
                                          "-p",
                                          "voxel_size:=0.005",
                                          "-p",
                                          "tabletop_only:=true",
                                          "-p",
                                          "objects:=True",
                                          "-p",
                                          "viewpoint:=[0.0, -1, 1.5]",
                                          "-p",
                                          "retries:=2",
                                          "-p",
                                          "units:=mm",
                                          "-p",
                                          "domain_id:=7",
                                          "-r",
                                          "__ns:=/robot",
                                          "-r",
                                          "__node:=labeler",
                                          "-r",
                                          "points:=/camera/depth/points"});
  EXPECT_EQ(s.parameters.server, "labeler:50051");  // HOST alone: port 50051, as the CLI
  EXPECT_EQ(s.parameters.model, "tabletop-kinect");
  EXPECT_DOUBLE_EQ(s.parameters.voxel_size, 0.005);
  EXPECT_TRUE(s.parameters.tabletop_only);
  EXPECT_TRUE(s.parameters.objects);
  ASSERT_TRUE(s.parameters.viewpoint.has_value());
  EXPECT_DOUBLE_EQ((*s.parameters.viewpoint)[1], -1.0);
  EXPECT_DOUBLE_EQ((*s.parameters.viewpoint)[2], 1.5);
  EXPECT_EQ(s.parameters.retries, 2);
  EXPECT_EQ(s.parameters.units, "mm");
  EXPECT_EQ(s.domain_id, 7u);
  EXPECT_EQ(s.node_name, "labeler");
  EXPECT_EQ(dds_topic(s, s.parameters.input_topic), "rt/camera/depth/points");
  EXPECT_EQ(dds_topic(s, s.parameters.output_topic), "rt/robot/points_labeled");
  EXPECT_EQ(dds_topic(s, s.parameters.summary_topic), "rt/robot/points_labeled_summary");
}

TEST(Ros2Arguments, TheDomainComesFromRosDomainIdUnlessGiven) {
  setenv("ROS_DOMAIN_ID", "12", 1);
  EXPECT_EQ(parse_arguments({}).domain_id, 12u);
  EXPECT_EQ(parse_arguments({"-p", "domain_id:=3"}).domain_id, 3u);
  unsetenv("ROS_DOMAIN_ID");
  EXPECT_EQ(parse_arguments({}).domain_id, 0u);
}

TEST(Ros2Arguments, RefusesWhatIsWrong) {
  unsetenv("ROS_DOMAIN_ID");
  for (const std::vector<std::string>& bad :
       std::vector<std::vector<std::string>>{{"-p", "voxel_size:=abc"},
                                             {"-p", "no_such:=1"},
                                             {"-p", "confidence:=yes"},
                                             {"-p", "viewpoint:=[1, 2]"},
                                             {"-p", "domain_id:=233"},
                                             {"-p", "retries:=0"},
                                             {"-p", "units:=feet"},
                                             {"-p", "objects:=true"},  // without tabletop_only
                                             {"-p", "server:=host:99999"},
                                             {"-r", "__ns:=robot"},
                                             {"-p", "input_topic:=a//b"},
                                             {"-p"},
                                             {"stray"}})
    EXPECT_THROW(parse_arguments(bad), std::invalid_argument) << bad.back();
}

// A parameters file in the test's temporary directory.
std::string params_file(const std::string& name, const std::string& yaml) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("primlabel_ros2_" + std::to_string(::getpid()) + "_" + name + ".yaml"))
                               .string();
  std::ofstream(path) << yaml;
  return path;
}

// As launch_ros writes a node's parameters (PyYAML: a list at its key's indentation).
constexpr const char* kLaunchFile = R"(/**:
  ros__parameters:
    server: 127.0.0.1:50051
    model: 'tabletop-kinect'   # a comment
    voxel_size: 0.005
    viewpoint:
    - 0.0
    - -1
    - 1.5
    use_sim_time: true
    qos_overrides:
      /points:
        subscription:
          reliability: reliable
          depth: 10
          history: keep_last
      /points_labeled:
        publisher:
          durability: transient_local
)";

TEST(Ros2ParamsFile, LaunchStyleFileSetsParametersAndQosOverrides) {
  unsetenv("ROS_DOMAIN_ID");
  const std::string file = params_file("launch", kLaunchFile);
  const Ros2Settings s = parse_arguments({"--ros-args", "--params-file", file});
  EXPECT_EQ(s.parameters.server, "127.0.0.1:50051");
  EXPECT_EQ(s.parameters.model, "tabletop-kinect");
  EXPECT_DOUBLE_EQ(s.parameters.voxel_size, 0.005);
  ASSERT_TRUE(s.parameters.viewpoint.has_value());
  EXPECT_DOUBLE_EQ((*s.parameters.viewpoint)[1], -1.0);
  EXPECT_TRUE(s.use_sim_time);
  EXPECT_EQ(s.input_qos.reliability, DDS_RELIABILITY_RELIABLE);
  EXPECT_EQ(s.input_qos.depth, 10);
  EXPECT_EQ(s.input_qos.history, DDS_HISTORY_KEEP_LAST);
  EXPECT_EQ(s.output_qos.durability, DDS_DURABILITY_TRANSIENT_LOCAL);
  EXPECT_FALSE(s.summary_qos.durability.has_value());
  // Without the file the input stays best effort, keep last 1.
  const Ros2Settings plain = parse_arguments({});
  EXPECT_FALSE(plain.input_qos.reliability.has_value());
  EXPECT_FALSE(plain.use_sim_time);
}

TEST(Ros2ParamsFile, NodeKeysChooseTheEntriesAndLaterArgumentsWin) {
  unsetenv("ROS_DOMAIN_ID");
  const std::string file = params_file("nodes", R"(
/**:
  ros__parameters:
    model: everyone
    retries: 2
/robot/labeler:
  ros__parameters:
    model: "mine"
other_node:
  ros__parameters:
    no_such_parameter: 1
robot:
  "*":
    ros__parameters:
      deadline: 7.5
/**/labeler:
  ros__parameters:
    voxel_size: 0.01
)");
  const Ros2Settings s = parse_arguments(
      {"--params-file", file, "-r", "__ns:=/robot", "-r", "__node:=labeler", "-p", "retries:=3"});
  EXPECT_EQ(s.parameters.model, "mine");  // after /** in the file
  EXPECT_EQ(s.parameters.retries, 3);     // -p after the file
  EXPECT_DOUBLE_EQ(s.parameters.deadline, 7.5);
  EXPECT_DOUBLE_EQ(s.parameters.voxel_size, 0.01);
  // Another node's name: only /** applies.
  const Ros2Settings other = parse_arguments({"--params-file", file, "-r", "__node:=x"});
  EXPECT_EQ(other.parameters.model, "everyone");
  EXPECT_DOUBLE_EQ(other.parameters.voxel_size, 0.0);
  // A -p before the file is overridden by it.
  EXPECT_EQ(parse_arguments({"-p", "retries:=9", "--params-file", file}).parameters.retries, 2);

  EXPECT_TRUE(node_key_matches("/**", "/a/b/c"));
  EXPECT_TRUE(node_key_matches("labeler", "/labeler"));
  EXPECT_FALSE(node_key_matches("labeler", "/robot/labeler"));
  EXPECT_TRUE(node_key_matches("/*/labeler", "/robot/labeler"));
  EXPECT_FALSE(node_key_matches("/*/labeler", "/a/robot/labeler"));
  EXPECT_TRUE(node_key_matches("/**/labeler", "/labeler"));
  EXPECT_FALSE(node_key_matches("/**/labeler", "/robot/other"));
}

TEST(Ros2ParamsFile, RefusesWhatItCannotReadWithTheFileAndLine) {
  unsetenv("ROS_DOMAIN_ID");
  const auto refused = [](const std::string& yaml, const std::string& expected) {
    const std::string file = params_file("bad", yaml);
    try {
      parse_arguments({"--params-file", file});
      ADD_FAILURE() << "accepted:\n" << yaml;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(file), std::string::npos) << what;
      EXPECT_NE(what.find(expected), std::string::npos) << what;
    }
  };
  refused("/**:\n  ros__parameters:\n    no_such: 1\n", "unknown parameter 'no_such'");
  refused("/**:\n  ros__parameters:\n    voxel_size: abc\n", "must be a number");
  refused("/**:\n  ros__parameters: {model: x}\n", "line 2: a flow map");
  refused("/**:\n  ros__parameters:\n\tmodel: x\n", "line 3: a tab");
  refused("/**:\n  ros__parameters:\n    model:\n", "line 3: parameter model has no value");
  refused("/**:\n  model: x\n", "line 2: 'model' must be a node's name");
  refused("/**:\n  ros__parameters:\n    model: &a x\n", "anchors");
  refused("/**:\n  ros__parameters:\n    model: 'x\n", "does not end");
  refused("/**:\n  ros__parameters:\n    model: x\n      more: y\n", "line 4");
  refused("/**:\n  ros__parameters:\n    qos_overrides./nowhere.subscription.depth: 3\n",
          "the node subscribes to /points");
  EXPECT_THROW(parse_arguments({"--params-file", "/no/such/file.yaml"}), std::invalid_argument);
  EXPECT_THROW(parse_arguments({"--params-file", "/tmp"}), std::invalid_argument);
  EXPECT_THROW(parse_arguments({"--params-file"}), std::invalid_argument);
}

TEST(Ros2Arguments, QosOverridesNameTheResolvedTopicAndAreChecked) {
  unsetenv("ROS_DOMAIN_ID");
  const Ros2Settings s =
      parse_arguments({"-r", "__ns:=/robot", "-r", "points:=/camera/points", "-p",
                       "qos_overrides./camera/points.subscription.reliability:=reliable", "-p",
                       "qos_overrides./camera/points.subscription.history:=keep_all", "-p",
                       "qos_overrides./robot/points_labeled_summary.publisher.depth:=5"});
  EXPECT_EQ(s.input_qos.reliability, DDS_RELIABILITY_RELIABLE);
  EXPECT_EQ(s.input_qos.history, DDS_HISTORY_KEEP_ALL);
  EXPECT_EQ(s.summary_qos.depth, 5);
  EXPECT_FALSE(s.output_qos.depth.has_value());
  for (const char* bad :
       {"qos_overrides./points.subscription.reliability:=reliable",  // not the resolved name
        "qos_overrides./camera/points.publisher.depth:=3",           // the node reads it
        "qos_overrides./camera/points.subscription.reliability:=sometimes",
        "qos_overrides./camera/points.subscription.depth:=0",
        "qos_overrides./camera/points.subscription.depth:=101",  // kMaxQueuedSamples
        "qos_overrides./camera/points.subscription.deadline:=1", "qos_overrides.nonsense:=1"})
    EXPECT_THROW(parse_arguments({"-r", "__ns:=/robot", "-r", "points:=/camera/points", "-p", bad}),
                 std::invalid_argument)
        << bad;
}

TEST(Ros2Arguments, LogLevelAndUseSimTime) {
  unsetenv("ROS_DOMAIN_ID");
  EXPECT_EQ(parse_arguments({}).log_level, Severity::kInfo);
  EXPECT_EQ(parse_arguments({"--log-level", "DEBUG"}).log_level, Severity::kDebug);
  EXPECT_EQ(parse_arguments({"--log-level", "warn"}).log_level, Severity::kWarn);
  // A logger's own level: this node's logger is its name in its namespace, '.' for '/'.
  EXPECT_EQ(parse_arguments({"-r", "__ns:=/robot", "-r", "__node:=labeler", "--log-level",
                             "robot.labeler:=error"})
                .log_level,
            Severity::kError);
  EXPECT_EQ(parse_arguments({"--log-level", "rcl:=debug"}).log_level, Severity::kInfo);
  EXPECT_THROW(parse_arguments({"--log-level", "loud"}), std::invalid_argument);
  EXPECT_THROW(parse_arguments({"--log-level"}), std::invalid_argument);
  EXPECT_TRUE(parse_arguments({"-p", "use_sim_time:=true"}).use_sim_time);
  EXPECT_THROW(parse_arguments({"-p", "use_sim_time:=maybe"}), std::invalid_argument);
}

TEST(Ros2Discovery, TheVariablesBecomeCycloneConfigurationAsRmwCycloneddsMakesIt) {
  EXPECT_EQ(cyclone_config({}), "");  // Cyclone DDS's defaults, CYCLONEDDS_URI read by itself
  EXPECT_EQ(cyclone_config({"0", "SUBNET", "", "file:///etc/dds.xml"}), "");
  const std::string localhost =
      "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
      "address=\"127.0.0.1\"/></Interfaces></General></Domain></CycloneDDS>";
  EXPECT_EQ(cyclone_config({"1", "", "", ""}), localhost);
  EXPECT_EQ(cyclone_config({"", "LOCALHOST", "", ""}), localhost);
  // CYCLONEDDS_URI after the fragment, so what it sets wins.
  EXPECT_EQ(cyclone_config({"1", "", "", "file:///etc/dds.xml"}),
            localhost + ",file:///etc/dds.xml");
  EXPECT_EQ(cyclone_config({"", "OFF", "10.0.0.2; robot-2", ""}),
            "<CycloneDDS><Domain Id=\"any\"><General><AllowMulticast>false</AllowMulticast>"
            "</General><Discovery><ParticipantIndex>auto</ParticipantIndex><Peers><Peer "
            "address=\"10.0.0.2\"/><Peer address=\"robot-2\"/></Peers></Discovery></Domain>"
            "</CycloneDDS>");
  // ROS_LOCALHOST_ONLY=1 wins over the range and drops the static peers, as rcl does.
  EXPECT_EQ(cyclone_config({"1", "SUBNET", "10.0.0.2", ""}), localhost);
  EXPECT_THROW(cyclone_config({"yes", "", "", ""}), std::invalid_argument);
  EXPECT_THROW(cyclone_config({"", "everywhere", "", ""}), std::invalid_argument);
  EXPECT_THROW(cyclone_config({"", "", "a\"/><Evil/>", ""}), std::invalid_argument);
  std::string many;
  for (int k = 0; k < 33; ++k) many += "10.0.0." + std::to_string(k) + ";";
  EXPECT_THROW(cyclone_config({"", "", many, ""}), std::invalid_argument);

  setenv("ROS_LOCALHOST_ONLY", "1", 1);
  unsetenv("CYCLONEDDS_URI");
  EXPECT_EQ(parse_arguments({}).dds_config, localhost);
  setenv("ROS_LOCALHOST_ONLY", "2", 1);
  EXPECT_THROW(parse_arguments({}), std::invalid_argument);
  unsetenv("ROS_LOCALHOST_ONLY");
}

}  // namespace
}  // namespace primlabel::ros2node
