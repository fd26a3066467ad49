#include "primlabel/ros2/type_hash.hpp"

#include <openssl/evp.h>

#include <algorithm>
#include <stdexcept>

namespace primlabel::ros2node {

namespace {

using namespace field_type;

std::string json_of(const TypeDescription& type) {
  std::string out = "{\"type_name\": \"" + type.type_name + "\", \"fields\": [";
  for (std::size_t k = 0; k < type.fields.size(); ++k) {
    const FieldDescription& f = type.fields[k];
    if (k) out += ", ";
    out += "{\"name\": \"" + f.name + "\", \"type\": {\"type_id\": " + std::to_string(f.type_id) +
           ", \"capacity\": " + std::to_string(f.capacity) +
           ", \"string_capacity\": " + std::to_string(f.string_capacity) +
           ", \"nested_type_name\": \"" + f.nested_type_name + "\"}}";
  }
  return out + "]}";
}

FieldDescription field(std::string name, int type_id, std::string nested = "") {
  return {std::move(name), type_id, 0, 0, std::move(nested)};
}

const TypeDescription kTime{"builtin_interfaces/msg/Time",
                            {field("sec", kInt32), field("nanosec", kUint32)}};
const TypeDescription kHeader{
    "std_msgs/msg/Header", {field("stamp", kNested, kTime.type_name), field("frame_id", kString)}};
const TypeDescription kPointField{"sensor_msgs/msg/PointField",
                                  {field("name", kString), field("offset", kUint32),
                                   field("datatype", kUint8), field("count", kUint32)}};
const TypeDescription kPointCloud2{
    "sensor_msgs/msg/PointCloud2",
    {field("header", kNested, kHeader.type_name), field("height", kUint32), field("width", kUint32),
     field("fields", kNested + kUnboundedSequence, kPointField.type_name),
     field("is_bigendian", kBool), field("point_step", kUint32), field("row_step", kUint32),
     field("data", kUint8 + kUnboundedSequence), field("is_dense", kBool)}};
const TypeDescription kString_{"std_msgs/msg/String", {field("data", kString)}};

// rmw_dds_common as of Iron: a GID is 16 bytes.
const TypeDescription kGid{"rmw_dds_common/msg/Gid", {{"data", kUint8 + kArray, 16, 0, ""}}};
const TypeDescription kNodeEntitiesInfo{
    "rmw_dds_common/msg/NodeEntitiesInfo",
    {{"node_namespace", kBoundedString, 0, 256, ""},
     {"node_name", kBoundedString, 0, 256, ""},
     field("reader_gid_seq", kNested + kUnboundedSequence, kGid.type_name),
     field("writer_gid_seq", kNested + kUnboundedSequence, kGid.type_name)}};
const TypeDescription kParticipantEntitiesInfo{
    "rmw_dds_common/msg/ParticipantEntitiesInfo",
    {field("gid", kNested, kGid.type_name),
     field("node_entities_info_seq", kNested + kUnboundedSequence, kNodeEntitiesInfo.type_name)}};

}  // namespace

std::string type_description_json(const TypeDescription& type,
                                  std::vector<TypeDescription> referenced) {
  std::sort(
      referenced.begin(), referenced.end(),
      [](const TypeDescription& a, const TypeDescription& b) { return a.type_name < b.type_name; });
  std::string out =
      "{\"type_description\": " + json_of(type) + ", \"referenced_type_descriptions\": [";
  for (std::size_t k = 0; k < referenced.size(); ++k)
    out += (k ? ", " : "") + json_of(referenced[k]);
  return out + "]}";
}

std::string rihs01_type_hash(const TypeDescription& type,
                             const std::vector<TypeDescription>& referenced) {
  const std::string json = type_description_json(type, referenced);
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int size = 0;
  if (EVP_Digest(json.data(), json.size(), digest, &size, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("SHA-256 of a type description failed");
  static const char* const hex = "0123456789abcdef";
  std::string out = "RIHS01_";
  for (unsigned int k = 0; k < size; ++k) {
    out += hex[digest[k] >> 4];
    out += hex[digest[k] & 15];
  }
  return out;
}

std::string point_cloud2_type_hash() {
  return rihs01_type_hash(kPointCloud2, {kHeader, kTime, kPointField});
}
std::string string_type_hash() { return rihs01_type_hash(kString_, {}); }
std::string participant_entities_info_type_hash() {
  return rihs01_type_hash(kParticipantEntitiesInfo, {kGid, kNodeEntitiesInfo});
}

}  // namespace primlabel::ros2node
