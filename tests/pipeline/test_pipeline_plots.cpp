// The report pictures and tables: the confusion-matrix PNG, and Fig. 4's class-mean signatures
// with their histogram-intersection distances (CSV and PNG).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "png_decode.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/render/heatmap.hpp"
#include "primlabel/research/confusion_plot.hpp"
#include "primlabel/research/fig4.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

crf::ConfusionMatrix sample_confusion() {
  crf::ConfusionMatrix confusion({1, 2, 4});
  confusion.add(1, 1, 900);
  confusion.add(1, 4, 100);
  confusion.add(2, 2, 50);
  confusion.add(4, 1, 30);
  confusion.add(4, 4, 70);
  return confusion;
}

std::size_t count_color(const test::Decoded& png, std::uint32_t rgb) {
  return png.count(rgb, 0, 0, png.width, png.height);
}

TEST(PipelinePlots, ConfusionPngShowsSharesCountsAndNames) {
  test::TempDir dir;
  const crf::ConfusionMatrix confusion = sample_confusion();
  research::write_confusion_png(dir.file("c.png"), confusion,
                                {"plane", "cylinder-convex", "edge-convex"}, "scene");
  const test::Decoded png = test::decode_png(dir.file("c.png"));
  ASSERT_GT(png.width, 0) << "does not decode";
  // Three columns of cells plus names: wider than tall enough for 3 rows and upright names.
  EXPECT_GT(png.width, 300);
  EXPECT_LT(png.width, 1200);
  EXPECT_GT(png.height, 3 * 20 + Raster::text_width("cylinder-convex", 2));
  EXPECT_LT(png.height, 1200);
  // cylinder-convex is always right: a full-share cell; nothing is ever predicted from it as
  // plane: an empty cell; text in black and white.
  EXPECT_GT(count_color(png, blues(1.0)), 500u);
  EXPECT_GT(count_color(png, blues(0.0)), 500u);
  EXPECT_GT(count_color(png, blues(0.9)), 500u);  // plane row: 900 of 1000
  EXPECT_GT(count_color(png, 0xFFFFFF), 1000u);
  EXPECT_GT(png.distinct_colors(), 6u);

  // Predictions outside the classes add an "other" column.
  crf::ConfusionMatrix with_other = confusion;
  with_other.add(2, 0, 5);
  research::write_confusion_png(dir.file("o.png"), with_other, {}, "");
  EXPECT_GT(test::decode_png(dir.file("o.png")).width, png.width / 2);
  EXPECT_THROW(research::write_confusion_png("/nonexistent/dir/c.png", confusion, {}),
               std::runtime_error);
}

TEST(PipelinePlots, HikDistanceIsZeroForEqualAndOneForDisjointHistograms) {
  const std::vector<double> a{50, 50, 0, 0}, b{0, 0, 50, 50}, c{50, 0, 50, 0}, half{25, 25, 0, 0};
  EXPECT_DOUBLE_EQ(research::hik_distance(a, a), 0.0);
  EXPECT_DOUBLE_EQ(research::hik_distance(a, b), 1.0);
  EXPECT_DOUBLE_EQ(research::hik_distance(a, c), 0.5);
  EXPECT_DOUBLE_EQ(research::hik_distance(c, a), 0.5);
  EXPECT_DOUBLE_EQ(research::hik_distance(a, half), 0.0);  // normalised by the smaller mass
  EXPECT_DOUBLE_EQ(research::hik_distance(std::vector<double>(4, 0.0), std::vector<double>(4, 0.0)),
                   0.0);
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(PipelinePlots, Fig4OnOneSyntheticSceneIsAProperDistanceMatrix) {
  research::Fig4Options options;
  options.scenes = 1;
  options.threads = 2;
  const research::Fig4 fig4 = research::run_fig4(options);
  const auto& ids = fig4.signatures.class_ids;
  const auto index_of = [&](PrimitiveClass c) {
    return Eigen::Index(std::find(ids.begin(), ids.end(), class_id(c)) - ids.begin());
  };
  const Eigen::Index plane = index_of(PrimitiveClass::kPlane);
  const Eigen::Index cylinder = index_of(PrimitiveClass::kCylinderConvex);
  ASSERT_LT(plane, Eigen::Index(ids.size()));
  ASSERT_LT(cylinder, Eigen::Index(ids.size()));
  ASSERT_EQ(fig4.signatures.mean.cols(), kFpfhSize);
  ASSERT_EQ(fig4.hik.rows(), Eigen::Index(ids.size()));
  ASSERT_EQ(fig4.hik.cols(), Eigen::Index(ids.size()));
  for (Eigen::Index r = 0; r < fig4.hik.rows(); ++r) {
    EXPECT_EQ(fig4.hik(r, r), 0.0);
    // FPFH: three sub-histograms of 100 each.
    EXPECT_NEAR(fig4.signatures.mean.row(r).sum(), 300.0, 0.5);
    for (Eigen::Index c = 0; c < fig4.hik.cols(); ++c) {
      EXPECT_EQ(fig4.hik(r, c), fig4.hik(c, r));
      EXPECT_GE(fig4.hik(r, c), 0.0);
      EXPECT_LE(fig4.hik(r, c), 1.0);
    }
  }
  EXPECT_GT(fig4.hik(plane, cylinder), 0.2);

  test::TempDir dir;
  const std::string out = dir.file("fig4");
  research::write_fig4(fig4, out);
  const std::string signatures = read_text(out + "/fig4_signatures.csv");
  EXPECT_EQ(signatures.rfind("class,bin0,bin1,", 0), 0u);
  EXPECT_NE(signatures.find(",bin32\nplane,"), std::string::npos);
  EXPECT_EQ(test::count_lines(signatures), int(ids.size()) + 1);
  const std::string hik = read_text(out + "/fig4_hik.csv");
  EXPECT_EQ(hik.rfind("class,plane,cylinder-convex", 0), 0u);
  EXPECT_NE(hik.find("\nplane,0.000000,"), std::string::npos);
  for (const char* png : {"/fig4_signatures.png", "/fig4_hik.png"}) {
    const test::Decoded decoded = test::decode_png(out + png);
    EXPECT_GT(decoded.width, 300) << png;
    EXPECT_GT(decoded.distinct_colors(), 8u) << png;
  }
}

}  // namespace
}  // namespace primlabel
