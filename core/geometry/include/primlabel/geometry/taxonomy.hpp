#pragma once
// The geometric primitive classes every component labels points with, in one place. The numeric
// ids are part of the file formats (PCD `label` fields, model files): never renumber a class,
// only append new ones.
//
// Convex/concave follow the side the material is on: "convex" bulges toward the viewer (the
// outside of a can, a ball), "concave" is hollow toward the viewer (the inside wall of a mug, the
// inside of a bowl, the crease where a box stands on a table). For tori, torus-convex is the outer
// (elliptic) side of a ring and every rim (the lip of a mug, cup or bowl, whose neighbourhood at
// the descriptor scale wraps from the outer to the inner wall); torus-concave is the inner
// (saddle) side of a ring, around its hole.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace primlabel {

enum class PrimitiveClass : std::uint32_t {
  kUnknown = 0,  // unknown / other: no primitive, invalid points, clutter
  kPlane = 1,
  kCylinderConvex = 2,
  kCylinderConcave = 3,
  kEdgeConvex = 4,
  kEdgeConcave = 5,
  kCorner = 6,
  kTorusConvex = 7,
  kTorusConcave = 8,
  kSphereConvex = 9,
  kSphereConcave = 10,
};

inline constexpr std::uint32_t kPrimitiveClassCount = 11;

constexpr std::uint32_t class_id(PrimitiveClass c) { return static_cast<std::uint32_t>(c); }

// Every class in id order.
const std::vector<PrimitiveClass>& all_classes();

// The class with this id, or nothing for an id outside the taxonomy.
std::optional<PrimitiveClass> class_from_id(std::uint32_t id);

// Canonical name: lower case, words joined by '-' ("cylinder-convex"). Stable, used in files.
std::string_view name(PrimitiveClass c);

// Parses a canonical name; case-insensitive, '_' and ' ' accepted for '-', and "other" /
// "unknown/other" for kUnknown. Nothing when the name is not a class.
std::optional<PrimitiveClass> from_name(std::string_view name);

// Display colour 0xRRGGBB: distinct hues, convex/concave pairs in related colours.
std::uint32_t color(PrimitiveClass c);

// Labels as they appear in someone's file (ids and names) matched to the taxonomy.
// Text form, one class per line: `<id> <name>` ('#' starts a comment; ',', ':' or '=' may
// separate id and name), e.g. `primlabel-synth --list-classes` prints the taxonomy's own map.
class ClassMap {
 public:
  struct Entry {
    std::uint32_t id;    // the label value in the file
    std::string name;    // as given in the map
    PrimitiveClass cls;  // the taxonomy class the name denotes
  };

  ClassMap() = default;

  // The identity map: id = class id, name = canonical name.
  static ClassMap taxonomy();

  // Parses the text form. Throws std::invalid_argument naming `source` and the line for a
  // malformed line, a duplicate id, or a name that is not a taxonomy class.
  static ClassMap parse(std::string_view text, const std::string& source = "class map");

  // Adds one entry; throws std::invalid_argument for a duplicate id or an unknown name.
  void add(std::uint32_t id, const std::string& name);

  std::string to_text() const;
  const std::vector<Entry>& entries() const { return entries_; }
  bool empty() const { return entries_.empty(); }

  const Entry* find(std::uint32_t id) const;
  std::optional<PrimitiveClass> class_of(std::uint32_t id) const;

 private:
  std::vector<Entry> entries_;  // sorted by id
};

// File versions of ClassMap::parse / to_text; throw std::runtime_error naming the path when the
// file cannot be read or written (and std::invalid_argument for bad content, as parse does).
ClassMap read_class_map(const std::string& path);
void write_class_map(const std::string& path, const ClassMap& map);

}  // namespace primlabel
