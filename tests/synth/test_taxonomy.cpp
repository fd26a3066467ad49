// The class taxonomy: stable ids and names, colours, and class maps for users' labeled files.

#include <gtest/gtest.h>

#include <set>

#include "primlabel/geometry/taxonomy.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

TEST(Taxonomy, IdsAndNamesAreStable) {
  // These ids are written into files and models: changing one is a format break.
  const std::vector<std::pair<PrimitiveClass, std::string>> expected = {
      {PrimitiveClass::kUnknown, "unknown"},
      {PrimitiveClass::kPlane, "plane"},
      {PrimitiveClass::kCylinderConvex, "cylinder-convex"},
      {PrimitiveClass::kCylinderConcave, "cylinder-concave"},
      {PrimitiveClass::kEdgeConvex, "edge-convex"},
      {PrimitiveClass::kEdgeConcave, "edge-concave"},
      {PrimitiveClass::kCorner, "corner"},
      {PrimitiveClass::kTorusConvex, "torus-convex"},
      {PrimitiveClass::kTorusConcave, "torus-concave"},
      {PrimitiveClass::kSphereConvex, "sphere-convex"},
      {PrimitiveClass::kSphereConcave, "sphere-concave"}};
  ASSERT_EQ(all_classes().size(), expected.size());
  for (std::size_t id = 0; id < expected.size(); ++id) {
    EXPECT_EQ(class_id(expected[id].first), id);
    EXPECT_EQ(all_classes()[id], expected[id].first);
    EXPECT_EQ(name(expected[id].first), expected[id].second);
    EXPECT_EQ(class_from_id(std::uint32_t(id)), expected[id].first);
  }
  EXPECT_FALSE(class_from_id(kPrimitiveClassCount).has_value());
}

TEST(Taxonomy, NamesRoundTripAndAcceptVariants) {
  for (PrimitiveClass c : all_classes()) EXPECT_EQ(from_name(name(c)), c);
  EXPECT_EQ(from_name("Cylinder_Convex"), PrimitiveClass::kCylinderConvex);
  EXPECT_EQ(from_name(" edge concave "), PrimitiveClass::kEdgeConcave);
  EXPECT_EQ(from_name("other"), PrimitiveClass::kUnknown);
  EXPECT_FALSE(from_name("cone").has_value());
  EXPECT_FALSE(from_name("").has_value());
}

TEST(Taxonomy, ColoursAreDistinct) {
  std::set<std::uint32_t> colours;
  for (PrimitiveClass c : all_classes()) colours.insert(color(c));
  EXPECT_EQ(colours.size(), all_classes().size());
}

TEST(ClassMap, TaxonomyRoundTripsThroughText) {
  const ClassMap map = ClassMap::taxonomy();
  const ClassMap back = ClassMap::parse(map.to_text());
  ASSERT_EQ(back.entries().size(), all_classes().size());
  for (const auto& e : back.entries()) {
    EXPECT_EQ(e.id, class_id(e.cls));
    EXPECT_EQ(e.name, name(e.cls));
  }
  EXPECT_EQ(back.to_text().substr(0, 18), "0 unknown\n1 plane\n");
}

TEST(ClassMap, ParsesUsersMapsWithCommentsAndSeparators) {
  const ClassMap map = ClassMap::parse(
      "# my scans\n\n20 plane\n21: cylinder_convex  # cans\n3,Corner\n 7 = other\n");
  ASSERT_EQ(map.entries().size(), 4u);
  EXPECT_EQ(map.class_of(20), PrimitiveClass::kPlane);
  EXPECT_EQ(map.class_of(21), PrimitiveClass::kCylinderConvex);
  EXPECT_EQ(map.class_of(3), PrimitiveClass::kCorner);
  EXPECT_EQ(map.class_of(7), PrimitiveClass::kUnknown);
  EXPECT_FALSE(map.class_of(4).has_value());
  EXPECT_EQ(map.find(21)->name, "cylinder_convex");  // the user's spelling is kept
}

TEST(ClassMap, RejectsBadLinesNamingTheLine) {
  auto message = [](const std::string& text) {
    try {
      ClassMap::parse(text, "map.txt");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("1 plane\n1 corner\n").find("map.txt:2: label 1 is listed twice"),
            std::string::npos);
  EXPECT_NE(message("1 plane\n2 cone\n").find("map.txt:2: 'cone' is not a primitive class"),
            std::string::npos);
  EXPECT_NE(message("plane 1\n").find("map.txt:1: expected"), std::string::npos);
  EXPECT_NE(message("5\n").find("map.txt:1: expected"), std::string::npos);
  EXPECT_NE(message("5x plane\n").find("map.txt:1: expected"), std::string::npos);
}

TEST(ClassMap, FilesRoundTripAndMissingFilesNameThePath) {
  test::TempDir dir;
  write_class_map(dir.file("classes.txt"), ClassMap::taxonomy());
  EXPECT_EQ(read_class_map(dir.file("classes.txt")).to_text(), ClassMap::taxonomy().to_text());
  try {
    read_class_map(dir.file("missing.txt"));
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.txt"), std::string::npos);
  }
}

}  // namespace
}  // namespace primlabel
