// render_png: the PNG decodes to the requested size, points and legend are drawn, errors are clear.

#include <gtest/gtest.h>

#include <cstdio>

#include "png_decode.hpp"
#include "primlabel/render/colorize.hpp"
#include "primlabel/render/raster.hpp"
#include "primlabel/render/render.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using test::decode_png;
using test::Decoded;

TEST(Render, WritesAPngOfTheRequestedSizeWithPointsAndLegend) {
  test::TempDir dir;
  PointCloud cloud = test::plane_grid(0.0f, 0.0f, 0.5f, 0.004f);
  std::vector<std::uint32_t> colors(cloud.size(), 0xFF0000);
  RenderOptions options;
  options.width = 640;
  options.height = 480;
  options.view = RenderView::kTop;
  options.title = "Test";
  options.legend = {{"plane", 0x00FF00}, {"edge-convex", 0x0000FF}};
  render_png(cloud, colors, options, dir.file("plane.png"));

  const Decoded png = decode_png(dir.file("plane.png"));
  ASSERT_EQ(png.width, 640);
  ASSERT_EQ(png.height, 480);
  // Points fill the middle of the plot area; the background stays white at the corners.
  EXPECT_EQ(png.at(639, 0), 0xFFFFFFu);
  EXPECT_GT(png.count_mostly(16, 200, 100, 600, 400), 50000u);
  // The legend's swatches sit bottom-left and the title's dark text top-left.
  EXPECT_GT(png.count(0x00FF00, 0, 380, 200, 480), 30u);
  EXPECT_GT(png.count(0x0000FF, 0, 380, 200, 480), 30u);
  EXPECT_GT(png.count(0x202020, 0, 0, 100, 30), 20u);
}

TEST(Render, ViewsDifferAndNearPointsHideFarOnes) {
  test::TempDir dir;
  // Two squares, red above blue: from the top only red is seen.
  PointCloud cloud;
  std::vector<std::uint32_t> colors;
  for (float z : {0.0f, 0.5f})
    for (float x = -0.5f; x <= 0.5f; x += 0.01f)
      for (float y = -0.5f; y <= 0.5f; y += 0.01f) {
        cloud.xyz.emplace_back(x, y, z);
        colors.push_back(z > 0 ? 0xFF0000 : 0x0000FF);
      }
  cloud.width = std::uint32_t(cloud.size());
  RenderOptions options;
  options.width = options.height = 256;
  options.view = RenderView::kTop;
  render_png(cloud, colors, options, dir.file("top.png"));
  Decoded top = decode_png(dir.file("top.png"));
  EXPECT_GT(top.count_mostly(16, 0, 0, 256, 256), 10000u);
  EXPECT_EQ(top.count_mostly(0, 0, 0, 256, 256), 0u);

  // From a sensor below, looking up, only blue.
  cloud.viewpoint.origin = Vec3f(0, 0, -2);
  cloud.viewpoint.orientation = Eigen::Quaternionf::Identity();  // looking along +z
  options.view = RenderView::kSensor;
  render_png(cloud, colors, options, dir.file("sensor.png"));
  const Decoded sensor = decode_png(dir.file("sensor.png"));
  EXPECT_GT(sensor.count_mostly(0, 0, 0, 256, 256), 5000u);
  EXPECT_EQ(sensor.count_mostly(16, 0, 0, 256, 256), 0u);
}

// The lowest row with ink when `s` is drawn at the top-left of a white raster; -1 for none.
int lowest_ink_row(const std::string& s) {
  Raster raster(16, 16);
  raster.text(0, 0, s, 0x000000);
  for (int y = raster.height() - 1; y >= 0; --y)
    for (int x = 0; x < raster.width(); ++x)
      if (raster.at(x, y) != 0xFFFFFF) return y;
  return -1;
}

TEST(RenderFont, DescendersReachBelowTheBaseline) {
  const int baseline = lowest_ink_row("H");  // capitals stand on the baseline: row 6 of 5x7
  ASSERT_EQ(baseline, 6);
  for (const char* flat : {"a", "x", "o", "n", "E"})
    EXPECT_EQ(lowest_ink_row(flat), baseline) << flat;
  for (const char* descending : {"g", "j", "p", "q", "y"}) {
    EXPECT_GT(lowest_ink_row(descending), baseline) << descending;
    EXPECT_LT(lowest_ink_row(descending), Raster::text_height()) << descending;  // laid out
  }
}

TEST(Render, ClearErrors) {
  const PointCloud cloud = test::plane_grid(0, 0, 0.1f, 0.01f);
  const std::vector<std::uint32_t> colors(cloud.size(), 0);
  try {
    render_png(cloud, colors, RenderOptions{}, "/nonexistent/dir/out.png");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot write PNG '/nonexistent/dir/out.png'"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(render_png(cloud, std::vector<std::uint32_t>(3), RenderOptions{}, "x.png"),
               std::invalid_argument);
  RenderOptions tiny;
  tiny.width = 10;
  EXPECT_THROW(render_png(cloud, colors, tiny, "x.png"), std::invalid_argument);
}

TEST(Colorize, ClassesSegmentsAndValues) {
  PointCloud cloud = test::random_box(4, 1.0f, 2);
  cloud.labels = {1, 1, 6, 42};
  const Coloring classes = color_by_class(cloud, ClassMap::taxonomy());
  EXPECT_EQ(classes.rgb[0], color(PrimitiveClass::kPlane));
  EXPECT_EQ(classes.rgb[2], color(PrimitiveClass::kCorner));
  ASSERT_EQ(classes.legend.size(), 3u);
  EXPECT_EQ(classes.legend[0].name, "plane 50.0%");
  EXPECT_EQ(classes.legend[1].name, "corner 25.0%");
  EXPECT_EQ(classes.legend[2].name, "label 42 25.0%");

  const Coloring segments = color_by_segment(cloud);
  EXPECT_EQ(segments.rgb[0], segments.rgb[1]);
  EXPECT_NE(segments.rgb[0], segments.rgb[2]);
  EXPECT_EQ(segments.legend.size(), 3u);

  const Coloring values = color_by_value({0.0f, 1.0f, NAN, 0.5f}, "curvature");
  EXPECT_EQ(values.rgb[0], viridis(0));
  EXPECT_EQ(values.rgb[1], viridis(1));
  EXPECT_EQ(values.legend.size(), 3u);
  EXPECT_THROW(color_by_rgb(cloud), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel
