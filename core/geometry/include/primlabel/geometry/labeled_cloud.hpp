#pragma once
// Labeled clouds as training and evaluation data: any PCD/PLY with an integer `label` field, its
// labels mapped to taxonomy classes through a ClassMap; and the tags primlabel-synth records in a
// file's header (label radius, sensor, seed, class list) as comment lines, which every PCD and PLY
// reader skips: `# primlabel <key> <value>` in PCD, `comment primlabel <key> <value>` in PLY.

#include <map>
#include <optional>
#include <string>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel {

using CloudTags = std::map<std::string, std::string>;

// Writes the cloud (format by extension, as write_cloud) with `tags` in its header. Keys are
// single words; values single lines.
void write_tagged_cloud(const std::string& path, const PointCloud& cloud, const CloudTags& tags,
                        const CloudWriteOptions& options = {});

// The tags in a file's header (empty when it has none). Throws IoError if it cannot be read.
CloudTags read_cloud_tags(const std::string& path);

// Class-map text in one tag value ("0:unknown 1:plane ...") and back.
std::string class_map_tag(const ClassMap& map);
ClassMap class_map_from_tag(const std::string& value);

// Reads a cloud whose integer `label` field holds class labels and replaces every label by its
// taxonomy class id through `map`. Points with non-finite coordinates become kUnknown whatever
// their label (e.g. label 0 of invalid Kinect pixels). Throws IoError naming the file when it has
// no label field, and when a valid point's label is not in the map (naming the label and how many
// points carry it).
PointCloud load_labeled_cloud(const std::string& path, const ClassMap& map);

// As above with the file's own class list (the `classes` tag primlabel-synth writes), or the
// taxonomy's ids when it has none.
PointCloud load_labeled_cloud(const std::string& path);

}  // namespace primlabel
