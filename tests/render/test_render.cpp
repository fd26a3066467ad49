// render_png: the PNG decodes to the requested size, points and legend are drawn, errors are clear.

#include <gtest/gtest.h>

#include <cstdio>

#include "png_decode.hpp"
#include "primlabel/render/box_outlines.hpp"
#include "primlabel/render/colorize.hpp"
#include "primlabel/render/primitive_outlines.hpp"
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

// crop_to_points: a wide scene leaves no empty band; the height never drops below the legend's.
TEST(Render, CropToPointsFitsTheHeightToTheScene) {
  test::TempDir dir;
  PointCloud strip;  // 1.0 x 0.2 m seen from the top (the sensor at the origin): an aspect of 5
  for (float x = -0.5f; x <= 0.5f; x += 0.01f)
    for (float y = 0; y <= 0.2f; y += 0.01f) strip.xyz.emplace_back(x, y, 0.0f);
  strip.width = std::uint32_t(strip.size());
  const std::vector<std::uint32_t> colors(strip.size(), 0xFF0000);
  RenderOptions options;
  options.width = 640;
  options.height = 480;
  options.view = RenderView::kTop;
  options.crop_to_points = true;
  render_png(strip, colors, options, dir.file("strip.png"));
  const Decoded cropped = decode_png(dir.file("strip.png"));
  EXPECT_EQ(cropped.width, 640);
  EXPECT_LT(cropped.height, 200);  // ~628 / 5 plus margins, not 480
  EXPECT_GT(cropped.count(0xFF0000, 0, 0, 640, cropped.height) +
                cropped.count_mostly(16, 0, 0, 640, cropped.height),
            10000u);
  options.legend.assign(12, {"a class 10.0%", 0x00FF00});  // 12 rows need more than the strip
  render_png(strip, colors, options, dir.file("legend.png"));
  EXPECT_GT(decode_png(dir.file("legend.png")).height, 12 * 20);
}

// A camera's organised frame is seen from the sensor (upright: its y points down); an
// unorganised scan obliquely.
TEST(Render, OrganisedFramesAreSeenFromTheSensor) {
  PointCloud frame;
  frame.xyz.assign(12, Vec3f(0, 0, 1));
  frame.width = 4, frame.height = 3;
  EXPECT_EQ(natural_view(frame), RenderView::kSensor);
  frame.width = 12, frame.height = 1;
  EXPECT_EQ(natural_view(frame), RenderView::kOblique);
}

// A camera frame in its optical frame (x right, y down, z forward): a table 0.4 m below the
// sensor with a box standing on it, 50 x 40 points.
PointCloud optical_table_frame() {
  PointCloud frame;
  frame.width = 50, frame.height = 40;
  for (int r = 0; r < 40; ++r)
    for (int c = 0; c < 50; ++c) {
      const float u = float(c) / 49;
      if (r < 10)  // the box's front face
        frame.xyz.emplace_back(-0.1f + 0.2f * u, 0.2f + 0.02f * float(r), 0.9f);
      else  // the table top
        frame.xyz.emplace_back(-0.5f + u, 0.4f, 0.8f + 0.8f * float(r - 10) / 29);
    }
  return frame;
}

// PCL's office1.pcd: an organised frame whose VIEWPOINT holds a rotation while its points are in
// the optical frame. Seen through that pose every point is behind the sensor; the picture still
// shows them.
TEST(Render, ASensorViewpointThatLooksAwayStillShowsThePoints) {
  test::TempDir dir;
  PointCloud frame = optical_table_frame();
  frame.viewpoint.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.5f * M_PI, Vec3f::UnitX()));
  const std::vector<std::uint32_t> colors(frame.size(), 0xFF0000);
  RenderOptions options;
  options.width = 320;
  options.height = 240;
  options.view = natural_view(frame);
  ASSERT_EQ(options.view, RenderView::kSensor);
  render_png(frame, colors, options, dir.file("rotated.png"));
  const Decoded rotated = decode_png(dir.file("rotated.png"));
  EXPECT_GT(rotated.count_mostly(16, 0, 0, rotated.width, rotated.height), 5000u);

  // A VIEWPOINT that sees the points is still the one used: the same frame moved into the
  // rotated sensor's world looks as the unrotated frame did.
  PointCloud moved = frame;
  for (Vec3f& p : moved.xyz) p = frame.viewpoint.orientation * p;
  render_png(moved, colors, options, dir.file("moved.png"));
  frame.viewpoint = {};
  render_png(frame, colors, options, dir.file("plain.png"));
  const Decoded moved_png = decode_png(dir.file("moved.png"));
  const Decoded plain_png = decode_png(dir.file("plain.png"));
  ASSERT_EQ(moved_png.rgb.size(), plain_png.rgb.size());
  const std::size_t differ = moved_png.pixels_differing_from(plain_png);
  EXPECT_LT(differ, plain_png.rgb.size() / 100) << differ;
}

// Box outlines: six polylines over the twelve edges, the label on the first.
TEST(BoxOutlines, TwelveEdgesAndALabel) {
  const std::vector<Overlay> box =
      box_outline(Vec3f(0, 0, 0), Vec3f(1, 2, 3), 0x123456, "object 7");
  ASSERT_EQ(box.size(), 6u);
  std::size_t segments = 0;
  for (const Overlay& o : box) {
    segments += o.closed ? o.points.size() : o.points.size() - 1;
    EXPECT_EQ(o.rgb, 0x123456u);
  }
  EXPECT_EQ(segments, 12u);
  EXPECT_EQ(box.front().label, "object 7");
  EXPECT_EQ(box.front().points.front(), Vec3f(0, 0, 3));  // at the top
  EXPECT_TRUE(box_outline(Vec3f(0, 0, 0), Vec3f(1, NAN, 1), 0).empty());
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

TEST(Render, OverlaysAreDrawnOverThePointsInTheirProjection) {
  test::TempDir dir;
  const PointCloud cloud = test::plane_grid(0.0f, 0.0f, 0.5f, 0.005f);  // x, y in [-0.5, 0.5]
  const std::vector<std::uint32_t> colors(cloud.size(), 0x00FF00);
  RenderOptions options;
  options.width = options.height = 256;
  options.view = RenderView::kTop;
  render_png(cloud, colors, options, dir.file("plain.png"));
  EXPECT_EQ(decode_png(dir.file("plain.png")).count(0xFF00FF, 0, 0, 256, 256), 0u);

  // A square of half the cloud's size, centred, hovering above it: drawn although the points'
  // z-buffer is in front of nothing (overlays ignore depth), and inside the cloud's footprint.
  options.overlays = {
      {{{-0.25f, -0.25f, 0.1f}, {0.25f, -0.25f, 0.1f}, {0.25f, 0.25f, 0.1f}, {-0.25f, 0.25f, 0.1f}},
       0xFF00FF,
       true}};
  render_png(cloud, colors, options, dir.file("square.png"));
  const Decoded png = decode_png(dir.file("square.png"));
  const std::size_t drawn = png.count(0xFF00FF, 0, 0, 256, 256);
  EXPECT_GT(drawn, 4u * 100u);  // four sides of about 125 pixels, 2 pixels thick
  EXPECT_LT(drawn, 4u * 130u * 3u);
  // Nothing of it near the image's border or at its centre: the square is where it belongs.
  EXPECT_EQ(png.count(0xFF00FF, 0, 0, 256, 40), 0u);
  EXPECT_EQ(png.count(0xFF00FF, 100, 100, 156, 156), 0u);
  // Closed: the left side is drawn too.
  EXPECT_GT(png.count(0xFF00FF, 40, 60, 90, 196), 100u);

  // Non-finite vertices and segments behind a pinhole camera are skipped, not drawn wrapped.
  options.view = RenderView::kSensor;
  options.overlays = {{{{0, 0, NAN}, {1, 1, 1}}, 0xFF00FF, false},
                      {{{0, 0, 1}, {0, 0, -1}}, 0xFF00FF, false}};
  PointCloud seen = cloud;
  seen.viewpoint.origin = Vec3f(0, 0, 1);
  EXPECT_NO_THROW(render_png(seen, colors, options, dir.file("sensor.png")));
}

namespace {
double distance_to_axis(const Vec3f& p, const primitives::Vec3d& center,
                        const primitives::Vec3d& axis) {
  const primitives::Vec3d d = p.cast<double>() - center;
  return (d - d.dot(axis) * axis).norm();
}
}  // namespace

TEST(PrimitiveOutlines, FollowEachModelsParameters) {
  using namespace primitives;
  std::vector<Primitive> fitted(6);
  fitted[0].class_id = 2;  // cylinder-convex
  fitted[0].model = CylinderModel{Vec3d(0.1, 0, 0.2), Vec3d::UnitZ(), 0.04, 0.12};
  fitted[1].class_id = 1;
  fitted[1].model =
      PlaneModel{Vec3d::UnitZ(), 0, Vec3d::Zero(), Vec3d::UnitX(), Vec3d::UnitY(), 0.8, 0.4};
  fitted[2].class_id = 9;
  fitted[2].model = SphereModel{Vec3d(0, 0, 0.3), 0.05};
  fitted[3].class_id = 4;
  fitted[3].model = LineModel{Vec3d(0, 0, 0.1), Vec3d::UnitY(), 0.3};
  fitted[4].class_id = 6;  // a corner: no model, nothing drawn
  fitted[5].class_id = 7;
  fitted[5].model = TorusModel{Vec3d::Zero(), Vec3d::UnitZ(), 0.1, 0.02};
  for (Primitive& p : fitted) p.confidence = 0.9;

  const std::vector<Overlay> all = primitive_outlines(fitted);
  // Cylinder: two end circles, four sides, the axis; plane: rectangle + normal; sphere: three
  // circles; line: one segment; torus: four circles and its axis.
  ASSERT_EQ(all.size(), 7u + 2u + 3u + 1u + 5u);
  for (int i = 0; i < 6; ++i)
    for (const Vec3f& p : all[i].points) {
      EXPECT_NEAR(distance_to_axis(p, Vec3d(0.1, 0, 0.2), Vec3d::UnitZ()), 0.04, 1e-6);
      EXPECT_LE(std::abs(p.z() - 0.2), 0.06 + 1e-6);
    }
  EXPECT_TRUE(all[0].closed && all[1].closed && !all[2].closed);
  EXPECT_NEAR(all[6].points[0].z(), 0.14, 1e-6);  // the axis from end to end
  EXPECT_NEAR(all[6].points[1].z(), 0.26, 1e-6);
  ASSERT_EQ(all[7].points.size(), 4u);  // the plane's rectangle: 0.8 x 0.4 around the centre
  EXPECT_NEAR(std::abs(all[7].points[0].x()), 0.4, 1e-6);
  EXPECT_NEAR(std::abs(all[7].points[0].y()), 0.2, 1e-6);
  for (int i = 9; i < 12; ++i)
    for (const Vec3f& p : all[i].points)
      EXPECT_NEAR((p.cast<double>() - Vec3d(0, 0, 0.3)).norm(), 0.05, 1e-6);
  EXPECT_NEAR((all[12].points[1] - all[12].points[0]).norm(), 0.3, 1e-6);
  for (const Vec3f& p : all[13].points) EXPECT_NEAR(p.head<2>().norm(), 0.12, 1e-6);
  for (const Vec3f& p : all[14].points) EXPECT_NEAR(p.head<2>().norm(), 0.08, 1e-6);
  // Each in its class's colour, darkened: distinct classes, distinct colours.
  EXPECT_NE(all[0].rgb, all[7].rgb);
  EXPECT_NE(all[0].rgb, color(PrimitiveClass::kCylinderConvex));

  // Below the confidence asked for, or degenerate (NaN radius, zero extent): not drawn.
  fitted[0].confidence = 0.2;
  std::get<SphereModel>(fitted[2].model).radius = NAN;
  std::get<PlaneModel>(fitted[1].model).extent_v = 0;
  EXPECT_EQ(primitive_outlines(fitted, {.min_confidence = 0.5}).size(), 1u + 5u);
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

  // Shares are of every point: one without a position (a NaN pixel) has an entry of its own, so
  // the legend agrees with the labels' own counts.
  PointCloud with_nan = cloud;
  with_nan.xyz.push_back(Vec3f::Constant(NAN));
  with_nan.labels.push_back(0);
  const Coloring counted = color_by_class(with_nan, ClassMap::taxonomy());
  ASSERT_EQ(counted.legend.size(), 4u);
  EXPECT_EQ(counted.legend[0].name, "plane 40.0%");
  EXPECT_EQ(counted.legend[3].name, "no point (NaN) 20.0%");

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
