// primlabel-ros2's command line and names without DDS: ROS 2's -p/-r arguments, the namespace
// and remaps, the topic names as rmw_cyclonedds has them on DDS (rt/...), and what is refused.

#include <gtest/gtest.h>

#include <cstdlib>

#include "ros2_arguments.hpp"
#include "ros2_names.hpp"

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
                                             {"-p", "objects:=true"},  // without tabletop_only
                                             {"-p", "server:=host:99999"},
                                             {"-r", "__ns:=robot"},
                                             {"-p", "input_topic:=a//b"},
                                             {"-p"},
                                             {"stray"}})
    EXPECT_THROW(parse_arguments(bad), std::invalid_argument) << bad.back();
}

}  // namespace
}  // namespace primlabel::ros2node
