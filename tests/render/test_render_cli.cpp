// primlabel-render as a user runs it: pictures of synthetic and real scans, exit codes, errors.

#include <gtest/gtest.h>
#include <png.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <utility>

#include "png_decode.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/primitives/primitives_json.hpp"
#include "primlabel/tabletop/objects_json.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using Result = test::CommandResult;

Result run(const std::string& command) { return test::run_command(command); }

std::string render_tool() { return test::binary("primlabel-render"); }
bool png_size(const std::string& path, int& width, int& height) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return false;
  width = int(image.width);
  height = int(image.height);
  png_image_free(&image);
  return true;
}

class RenderCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    const Result r =
        run(test::binary("primlabel-synth") +
            " --scene primitives --sensor lms400 --seed 2 -q -o " + dir_->file("prims.pcd"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string scene() { return dir_->file("prims.pcd"); }
  // The scene's picture, small and without a legend, so overlays show as changed pixels; the
  // output file follows.
  static std::string small_picture_command() {
    return render_tool() + " " + scene() + " --no-legend --width 320 --height 240 -o ";
  }
  // Least and greatest corner of the scene's finite points.
  static std::pair<Vec3f, Vec3f> scene_bounds() {
    const PointCloud cloud = read_cloud(scene());
    Vec3f lo = Vec3f::Constant(INFINITY), hi = -lo;
    for (const Vec3f& p : cloud.xyz)
      if (is_finite(p)) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    return {lo, hi};
  }
  static test::TempDir* dir_;
};
test::TempDir* RenderCli::dir_ = nullptr;

TEST_F(RenderCli, RendersLabelsRgbAndFieldsInEveryView) {
  const std::vector<std::string> variants = {
      "",
      "--field label --view top",
      "--field rgb --view sensor",
      "--field z --view oblique",
      "--field object --palette segments",
      "--field label --palette segments --no-legend --no-title"};
  for (std::size_t i = 0; i < variants.size(); ++i) {
    const std::string out = dir_->file(std::string("v").append(std::to_string(i)).append(".png"));
    const Result r = run(render_tool() + " " + scene() + " -o " + out +
                         " --width 320 --height 240 " + variants[i]);
    ASSERT_EQ(r.exit_code, 0) << variants[i] << ": " << r.output;
    EXPECT_EQ(r.output, "");
    int width = 0, height = 0;
    ASSERT_TRUE(png_size(out, width, height)) << variants[i];
    EXPECT_EQ(width, 320);
    EXPECT_EQ(height, 240);
  }
}

TEST_F(RenderCli, ClassMapNamesTheLegend) {
  const std::string map = dir_->file("map.txt");
  FILE* f = std::fopen(map.c_str(), "w");
  std::fputs("0 unknown\n1 plane\n", f);  // deliberately incomplete: the rest show as "label N"
  std::fclose(f);
  const Result r =
      run(render_tool() + " " + scene() + " -o " + dir_->file("m.png") + " --classes " + map);
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST_F(RenderCli, UsageErrorsExitWith2AndOneLine) {
  for (const std::string args :
       {" -o x.png --view side", "", " -o x.png --width 10", " -o x.png --palette rainbow"}) {
    const Result r = run(render_tool() + " " + scene() + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
    EXPECT_NE(r.output.find("primlabel-render: usage error"), std::string::npos) << r.output;
  }
}

// The tool writes PNG only: another extension is refused before anything is written.
TEST_F(RenderCli, ANonPngOutputNameIsAUsageErrorAndWritesNothing) {
  for (const std::string name : {"x.jpg", "x.JPEG", "x", "x.png.gz"}) {
    const std::string out = dir_->file(name);
    const Result r = run(render_tool() + " " + scene() + " -o " + out);
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
    EXPECT_NE(r.output.find("writes PNG only"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out)) << out;
  }
  const Result upper = run(render_tool() + " " + scene() + " -o " + dir_->file("X.PNG") +
                           " --width 320 --height 240");
  EXPECT_EQ(upper.exit_code, 0) << upper.output;
  EXPECT_TRUE(std::filesystem::exists(dir_->file("X.PNG")));
}

TEST_F(RenderCli, RuntimeErrorsExitWith1AndNameTheFile) {
  Result r = run(render_tool() + " /nonexistent/scan.pcd -o " + dir_->file("x.png"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("/nonexistent/scan.pcd"), std::string::npos) << r.output;
  r = run(render_tool() + " " + scene() + " -o /nonexistent/dir/x.png");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/dir/x.png"), std::string::npos) << r.output;
  r = run(render_tool() + " " + scene() + " -o " + dir_->file("x.png") + " --field fpfh");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("has no field 'fpfh' (fields: x y z label rgb object)"),
            std::string::npos)
      << r.output;
}

TEST_F(RenderCli, DrawsTheFittedPrimitivesOfAJsonFile) {
  // A cylinder standing in the scene's middle, as primlabel label --primitives writes it.
  const auto [lo, hi] = scene_bounds();
  primitives::Primitive can;
  can.class_id = class_id(PrimitiveClass::kCylinderConvex);
  can.model = primitives::CylinderModel{((lo + hi) / 2).cast<double>(), primitives::Vec3d::UnitZ(),
                                        0.15, 0.3};
  can.confidence = 0.8;
  can.points = 100;
  const std::string json = dir_->file("prims.json");
  { std::ofstream(json) << primitives::primitives_json(std::vector{can}); }
  const std::string base = small_picture_command();
  ASSERT_EQ(run(base + dir_->file("plain.png")).exit_code, 0);
  Result r = run(base + dir_->file("fits.png") + " --primitives " + json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const test::Decoded plain = test::decode_png(dir_->file("plain.png"));
  const std::size_t changed = test::decode_png(dir_->file("fits.png")).pixels_differing_from(plain);
  EXPECT_GT(changed, 400u) << changed;  // two circles, four sides and an axis
  // Below --min-confidence it is left out: the same picture as without.
  r = run(base + dir_->file("none.png") + " --primitives " + json + " --min-confidence 0.9");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(test::decode_png(dir_->file("none.png")).rgb, plain.rgb);

  // A missing or malformed file is an input error naming it, in one line.
  for (const std::string& bad : {dir_->file("absent.json"), scene()}) {
    r = run(base + dir_->file("bad.png") + " --primitives " + bad);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
    EXPECT_NE(r.output.find(bad), std::string::npos) << r.output;
  }
}

TEST_F(RenderCli, DrawsTheTableTopObjectsOfAJsonFile) {
  // One box around the scene's middle, as primlabel label --objects writes it.
  const auto [lo, hi] = scene_bounds();
  tabletop::TabletopObjects objects;
  objects.table = tabletop::TabletopTable{};
  tabletop::TabletopObject box;
  box.id = 1;
  box.points = 100;
  box.bounds_min = (0.75f * lo + 0.25f * hi).cast<double>();
  box.bounds_max = (0.25f * lo + 0.75f * hi).cast<double>();
  objects.objects.push_back(box);
  const std::string json = dir_->file("objects.json");
  { std::ofstream(json) << tabletop::objects_json(objects); }
  const std::string base = small_picture_command();
  ASSERT_EQ(run(base + dir_->file("plain_objects.png")).exit_code, 0);
  Result r = run(base + dir_->file("boxes.png") + " --objects " + json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::size_t changed =
      test::decode_png(dir_->file("boxes.png"))
          .pixels_differing_from(test::decode_png(dir_->file("plain_objects.png")));
  EXPECT_GT(changed, 300u) << changed;  // twelve edges
  r = run(base + dir_->file("bad.png") + " --objects " + scene());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(scene()), std::string::npos) << r.output;
}

TEST(RenderCliShared, MosdSegmentsFromTheSensor) {
  const std::string scan = test::shared_data("mosd/learn36.pcd");
  if (!std::filesystem::exists(scan)) GTEST_SKIP() << scan << " not present";
  test::TempDir dir;
  const Result r = run(render_tool() + " " + scan + " -o " + dir.file("learn36.png") +
                       " --field label --palette segments --view sensor --width 640 --height 480");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  int width = 0, height = 0;
  EXPECT_TRUE(png_size(dir.file("learn36.png"), width, height));
}

// Without --view, a camera frame is drawn from the camera (as primlabel label --png draws it) and
// an unorganised scan obliquely.
TEST(RenderCliShared, TheDefaultViewIsTheSensorsForACameraFrame) {
  const std::string scan = test::shared_data("mosd/learn36.pcd");
  if (!std::filesystem::exists(scan)) GTEST_SKIP() << scan << " not present";
  test::TempDir dir;
  const std::string base = render_tool() + " " + scan + " --width 320 --height 240 -o ";
  const auto bytes = [&](const std::string& view) {
    const std::string out = dir.file(view.empty() ? "default.png" : view + ".png");
    const Result r = run(base + out + (view.empty() ? "" : " --view " + view));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(out, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  };
  const std::string by_default = bytes("");
  ASSERT_FALSE(by_default.empty());
  EXPECT_EQ(by_default, bytes("sensor"));
  EXPECT_NE(by_default, bytes("oblique"));
}

}  // namespace
}  // namespace primlabel
