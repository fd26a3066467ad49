#include "primlabel/geometry/labeled_cloud.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <stdexcept>

#include "primlabel/geometry/cloud_io.hpp"

namespace primlabel {
namespace {

bool is_ply(const std::string& path) {
  std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".ply";
}

// The tags as header comment lines "primlabel <key> <value>" (read_cloud_tags reads them back).
HeaderComments tag_comments(const CloudTags& tags) {
  HeaderComments out;
  for (const auto& [key, value] : tags) {
    if (key.empty() || key.find_first_of(" \t\r\n") != std::string::npos)
      throw std::invalid_argument("tag key '" + key + "' must be one word");
    if (value.find_first_of("\r\n") != std::string::npos)
      throw std::invalid_argument("tag '" + key + "' must be one line");
    out.push_back("primlabel " + key + " " + value);
  }
  return out;
}

}  // namespace

void write_tagged_cloud(const std::string& path, const PointCloud& cloud, const CloudTags& tags,
                        const CloudWriteOptions& options) {
  write_cloud(path, cloud, tag_comments(tags), options);
}

CloudTags read_cloud_tags(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open");
  CloudTags tags;
  const bool ply = is_ply(path);
  const std::string prefix = ply ? "comment primlabel " : "# primlabel ";
  std::string line;
  for (int count = 0; count < 10000 && std::getline(in, line); ++count) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.rfind(prefix, 0) == 0) {
      const std::string rest = line.substr(prefix.size());
      const std::size_t space = rest.find(' ');
      tags[rest.substr(0, space)] = space == std::string::npos ? "" : rest.substr(space + 1);
    }
    if (line.rfind(ply ? "end_header" : "DATA", 0) == 0) break;
  }
  return tags;
}

std::string class_map_tag(const ClassMap& map) {
  std::string out;
  for (const ClassMap::Entry& e : map.entries()) {
    out += out.empty() ? "" : " ";
    out += std::to_string(e.id) + ":" + e.name;
  }
  return out;
}

ClassMap class_map_from_tag(const std::string& value) {
  std::string text = value;
  std::replace(text.begin(), text.end(), ' ', '\n');
  return ClassMap::parse(text, "classes tag");
}

PointCloud load_labeled_cloud(const std::string& path, const ClassMap& map) {
  PointCloud cloud = read_cloud(path);
  if (!cloud.has_labels())
    throw IoError(path + ": no integer 'label' field, so it cannot serve as labeled data");
  std::map<std::uint32_t, std::size_t> unmapped;  // label -> points
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!is_finite(cloud.xyz[i])) {
      cloud.labels[i] = class_id(PrimitiveClass::kUnknown);
      continue;
    }
    const auto cls = map.class_of(cloud.labels[i]);
    if (!cls) {
      ++unmapped[cloud.labels[i]];
      continue;
    }
    cloud.labels[i] = class_id(*cls);
  }
  if (!unmapped.empty()) {
    std::string known;
    for (const ClassMap::Entry& e : map.entries()) {
      known += known.empty() ? "" : ", ";
      known += std::to_string(e.id);
    }
    const auto& [label, points] = *unmapped.begin();
    throw IoError(
        path + ": label " + std::to_string(label) + " (" + std::to_string(points) + " points" +
        (unmapped.size() > 1
             ? ", and " + std::to_string(unmapped.size() - 1) + " more unmapped labels"
             : std::string()) +
        ") is not in the class map (it lists " + (known.empty() ? "nothing" : known) + ")");
  }
  return cloud;
}

PointCloud load_labeled_cloud(const std::string& path) {
  const CloudTags tags = read_cloud_tags(path);
  const auto classes = tags.find("classes");
  if (classes == tags.end()) return load_labeled_cloud(path, ClassMap::taxonomy());
  ClassMap map;
  try {
    map = class_map_from_tag(classes->second);
  } catch (const std::invalid_argument& e) {
    throw IoError(path + ": " + e.what());
  }
  return load_labeled_cloud(path, map);
}

}  // namespace primlabel
