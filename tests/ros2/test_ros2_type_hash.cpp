// ROS 2's RIHS01 type hashes as the node computes them for its endpoints' USER_DATA. The
// std_msgs/msg/String and sensor_msgs/msg/PointCloud2 values are the ones Iron and Jazzy
// publish for those types (e.g. `ros2 topic info -v` on a Jazzy robot); the JSON is what
// rosidl_generator_type_description hashes.

#include <gtest/gtest.h>

#include "primlabel/ros2/type_hash.hpp"

namespace primlabel::ros2node {
namespace {

TEST(Ros2TypeHash, TheJsonIsRosidlsHashedForm) {
  EXPECT_EQ(type_description_json({"std_msgs/msg/String", {{"data", field_type::kString}}}, {}),
            "{\"type_description\": {\"type_name\": \"std_msgs/msg/String\", \"fields\": "
            "[{\"name\": \"data\", \"type\": {\"type_id\": 17, \"capacity\": 0, "
            "\"string_capacity\": 0, \"nested_type_name\": \"\"}}]}, "
            "\"referenced_type_descriptions\": []}");
  // Referenced types sorted by name, whatever order they are given in.
  const TypeDescription a{"a/msg/A", {}}, b{"b/msg/B", {}};
  EXPECT_EQ(type_description_json(a, {b, a}), type_description_json(a, {a, b}));
}

TEST(Ros2TypeHash, EqualsWhatRos2PublishesForTheNodesTypes) {
  EXPECT_EQ(string_type_hash(),
            "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18");
  EXPECT_EQ(point_cloud2_type_hash(),
            "RIHS01_9198cabf7da3796ae6fe19c4cb3bdd3525492988c70522628af5daa124bae2b5");
  // Not checked against a ROS 2 installation: the same algorithm on rmw_dds_common's
  // definition as of Iron (computed independently in Python when written).
  EXPECT_EQ(participant_entities_info_type_hash(),
            "RIHS01_91a0593bacdcc50ea9bdcf849a938b128412cc1ea821245c663bcd26f83c295e");
}

}  // namespace
}  // namespace primlabel::ros2node
