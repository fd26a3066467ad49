#pragma once
// ROS 2's type hashes (Iron and later put `typehash=RIHS01_<hex>;` in every endpoint's
// USER_DATA), computed as rosidl_generator_type_description does: SHA-256 over the JSON of the
// type's description and of every type it references (sorted by name), field default values
// left out, written as Python's json.dumps writes it (", " and ": " separators).

#include <string>
#include <vector>

namespace primlabel::ros2node {

// type_description_interfaces/msg/FieldType's ids (the ones these messages use).
namespace field_type {
constexpr int kNested = 1, kUint8 = 3, kInt32 = 6, kUint32 = 7, kBool = 15, kString = 17,
              kBoundedString = 21;
constexpr int kArray = 48, kUnboundedSequence = 144;  // added to an element's id
}  // namespace field_type

struct FieldDescription {
  std::string name;
  int type_id = 0;
  int capacity = 0;         // an array's length or a bounded sequence's bound
  int string_capacity = 0;  // a bounded string's bound
  std::string nested_type_name;
};

struct TypeDescription {
  std::string type_name;  // "sensor_msgs/msg/PointCloud2"
  std::vector<FieldDescription> fields;
};

// The hashed JSON of `type` with the descriptions of the types it references, in any order.
std::string type_description_json(const TypeDescription& type,
                                  std::vector<TypeDescription> referenced);

// "RIHS01_" and the SHA-256 of type_description_json, in lower-case hex.
std::string rihs01_type_hash(const TypeDescription& type,
                             const std::vector<TypeDescription>& referenced);

// The hashes of the node's messages.
std::string point_cloud2_type_hash();               // sensor_msgs/msg/PointCloud2
std::string string_type_hash();                     // std_msgs/msg/String
std::string participant_entities_info_type_hash();  // rmw_dds_common/msg/ParticipantEntitiesInfo

}  // namespace primlabel::ros2node
