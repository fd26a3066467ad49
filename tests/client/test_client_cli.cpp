// The `primlabel` CLI as a script runs it, against the in-process fake server: output files and
// the documented exit codes (0 ok, 1 file, 2 usage, 3 unavailable, 4 rejected); the server
// address from --server or $PRIMLABEL_SERVER; what `info` prints for people.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/class_fields.hpp"
#include "common/human_format.hpp"
#include "common/labeled_output.hpp"
#include "common/server_address.hpp"
#include "fake_labeler.hpp"
#include "png_decode.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/primitives/primitives_json.hpp"
#include "primlabel/tabletop/objects_json.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using test::FakeServer;

std::string cli() { return test::binary("primlabel"); }

// A small cloud whose fake labels are i % 5.
void write_scan(const std::string& path, std::size_t n = 300) {
  PointCloud cloud;
  cloud.resize_unorganized(n);
  for (std::size_t i = 0; i < n; ++i) cloud.xyz[i] = Vec3f(float(i % 5), 0.01f * i, 0.3f);
  write_cloud(path, cloud);
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// An address nothing listens on.
std::string dead_address() { return FakeServer().address(); }

// The per-class field names, case by case as the Python client checks them too.
TEST(ClassFields, ProbabilityFieldNamesAsTheSharedCasesSay) {
  std::ifstream in(test::test_data("probability_field_names.tsv"));
  ASSERT_TRUE(in.good());
  int cases = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const std::size_t a = line.find('\t'), b = line.find('\t', a + 1);
    ASSERT_NE(b, std::string::npos) << line;
    const std::string name = line.substr(0, a), expected = line.substr(b + 1);
    const auto id = static_cast<std::uint32_t>(std::stoul(line.substr(a + 1, b - a - 1)));
    EXPECT_EQ(client::tools::probability_field_name(name, id), expected) << line;
    ++cases;
  }
  EXPECT_GE(cases, 5);
}

TEST(ClientCli, HelpListsTheExitCodes) {
  const auto r = test::run_command(cli() + " --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("1 input/output file error, 2 usage error, 3 server unavailable"),
            std::string::npos)
      << r.output;
}

// The scheme every primlabel binary shares: 2 = bad usage, 1 = the run failed.
TEST(ClientCli, UsageErrorsExitTwoWithOneLine) {
  for (const char* args : {"", " frobnicate", " label", " --deadline -3 health"}) {
    const auto r = test::run_command(cli() + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  }
}

TEST(ClientCli, HealthAndModels) {
  FakeServer server;
  auto r = test::run_command(cli() + " --server " + server.address() + " health");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "SERVING\n");
  r = test::run_command(cli() + " --server " + server.address() + " models");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("fake"), std::string::npos) << r.output;
  r = test::run_command(cli() + " --server " + server.address() + " info fake");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("class-2"), std::string::npos) << r.output;
  server.set_serving(false);
  r = test::run_command(cli() + " --server " + server.address() + " health");
  EXPECT_EQ(r.exit_code, 3) << r.output;
}

TEST(ClientCli, LabelWritesLabelsDescriptorsProbabilitiesAndPng) {
  FakeServer server;
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  const auto r = test::run_command(cli() + " --server " + server.address() + " label " +
                                   dir.file("scan.pcd") + " -o " + dir.file("out.pcd") +
                                   " --descriptors --probabilities --png --chunk-points 64");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PointCloud out = read_cloud(dir.file("out.pcd"));
  ASSERT_EQ(out.labels.size(), 300u);
  for (std::size_t i = 0; i < 300; ++i) ASSERT_EQ(out.labels[i], i % 5);
  // The field is named as the server names its descriptors (the fake serves the paper's).
  EXPECT_EQ(out.find_field("fpfh"), nullptr);
  ASSERT_NE(out.find_field("fpfh_paper"), nullptr);
  EXPECT_EQ(out.find_field("fpfh_paper")->count, 33);
  // One scalar field per class, named by the class (the fake names them class-0 .. class-2).
  EXPECT_EQ(out.find_field("probability"), nullptr);
  for (const char* name : {"prob_class_0", "prob_class_1", "prob_class_2"}) {
    ASSERT_NE(out.find_field(name), nullptr) << name;
    EXPECT_EQ(out.find_field(name)->count, 1) << name;
  }
  EXPECT_TRUE(std::filesystem::exists(dir.file("out.png")));
  EXPECT_NE(r.output.find("300 points"), std::string::npos) << r.output;
}

// A label field of the input (its truth, its segments) is kept beside the predicted classes, and
// the CLI says so.
TEST(ClientCli, AnInputsOwnLabelFieldIsKeptAsInputLabel) {
  FakeServer server;
  test::TempDir dir;
  PointCloud scan;
  scan.resize_unorganized(300);
  scan.labels.resize(300);
  for (std::size_t i = 0; i < 300; ++i) {
    scan.xyz[i] = Vec3f(float(i % 5), 0.01f * i, 0.3f);
    scan.labels[i] = 20 + std::uint32_t(i % 3);
  }
  write_cloud(dir.file("truth.pcd"), scan);
  const auto r = test::run_command(cli() + " --server " + server.address() + " label " +
                                   dir.file("truth.pcd") + " -o " + dir.file("out.pcd"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("its own label field is kept as 'input_label'"), std::string::npos)
      << r.output;
  const PointCloud out = read_cloud(dir.file("out.pcd"));
  const FloatField* kept = out.find_field("input_label");
  ASSERT_NE(kept, nullptr);
  for (std::size_t i = 0; i < 300; ++i) {
    ASSERT_EQ(out.labels[i], i % 5);                     // the predicted classes
    ASSERT_EQ(kept->values[i], float(20 + i % 3)) << i;  // the input's own
  }
  // Without a label field: no note, no extra field.
  write_scan(dir.file("plain.pcd"));
  const auto plain = test::run_command(cli() + " --server " + server.address() + " label " +
                                       dir.file("plain.pcd") + " -o " + dir.file("plain_out.pcd"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_EQ(plain.output.find("input_label"), std::string::npos) << plain.output;
  EXPECT_EQ(read_cloud(dir.file("plain_out.pcd")).find_field("input_label"), nullptr);
}

// The CLI sends an organised file's width and height (so a server can pick the camera's model)
// and prints how the model was chosen.
TEST(ClientCli, LabelSendsTheFramesShapeAndPrintsHowTheModelWasChosen) {
  FakeServer server;
  test::TempDir dir;
  PointCloud frame;
  frame.resize_unorganized(300);
  for (std::size_t i = 0; i < 300; ++i) frame.xyz[i] = Vec3f(float(i % 5), 0.01f * i, 0.3f);
  frame.width = 20, frame.height = 15;
  write_cloud(dir.file("frame.pcd"), frame);
  write_scan(dir.file("scan.pcd"));
  const auto unnamed = test::run_command(cli() + " --server " + server.address() + " label " +
                                         dir.file("frame.pcd") + " -o " + dir.file("f.pcd"));
  ASSERT_EQ(unnamed.exit_code, 0) << unnamed.output;
  EXPECT_NE(unnamed.output.find("the default: the only model served"), std::string::npos)
      << unnamed.output;
  const auto named =
      test::run_command(cli() + " --server " + server.address() + " label " + dir.file("scan.pcd") +
                        " -o " + dir.file("s.pcd") + " --model fake");
  ASSERT_EQ(named.exit_code, 0) << named.output;
  EXPECT_NE(named.output.find("named by the request"), std::string::npos) << named.output;
  std::lock_guard lock(server.service.mutex);
  ASSERT_EQ(server.service.layouts.size(), 2u);
  EXPECT_EQ(server.service.layouts[0].width(), 20u);
  EXPECT_EQ(server.service.layouts[0].height(), 15u);
  EXPECT_EQ(server.service.layouts[1].height(), 0u);  // unorganised: no shape sent
}

// --every-point asks the server to describe every point (no plane cascade); without it the
// request leaves the server's default.
TEST(ClientCli, EveryPointReachesTheRequest) {
  FakeServer server;
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  const std::string base = cli() + " --server " + server.address() + " label " +
                           dir.file("scan.pcd") + " -o " + dir.file("out.pcd");
  const auto plain = test::run_command(base);
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const auto every = test::run_command(base + " --every-point");
  ASSERT_EQ(every.exit_code, 0) << every.output;
  std::lock_guard lock(server.service.mutex);
  ASSERT_EQ(server.service.options.size(), 2u);
  EXPECT_FALSE(server.service.options[0].every_point());
  EXPECT_TRUE(server.service.options[1].every_point());
}

// --primitives writes primlabel-eval's JSON from the summary's primitives (the fake's known
// instances, read back with the core's parser).
TEST(ClientCli, PrimitivesGoToTheirJsonFile) {
  FakeServer server;
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  const auto r = test::run_command(
      cli() + " --server " + server.address() + " label " + dir.file("scan.pcd") + " -o " +
      dir.file("out.pcd") + " --primitives " + dir.file("prims.json") + " --chunk-points 64");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto instances = primitives::parse_primitives_json(read_text(dir.file("prims.json")));
  ASSERT_EQ(instances.size(), 4u);
  const auto* plane = std::get_if<primitives::PlaneModel>(&instances[0].model);
  ASSERT_NE(plane, nullptr);
  EXPECT_EQ(plane->normal, primitives::Vec3d(0, 0, 1));
  EXPECT_DOUBLE_EQ(plane->offset, -0.3);
  EXPECT_DOUBLE_EQ(plane->extent_u, 3.0);
  EXPECT_EQ(instances[0].class_id, 1u);
  EXPECT_EQ(instances[0].points, 60u);
  EXPECT_EQ(instances[0].inliers, 50u);
  EXPECT_DOUBLE_EQ(instances[0].confidence, 0.9);
  const auto* cylinder = std::get_if<primitives::CylinderModel>(&instances[1].model);
  ASSERT_NE(cylinder, nullptr);
  EXPECT_DOUBLE_EQ(cylinder->radius, 0.04);
  EXPECT_DOUBLE_EQ(cylinder->height, 0.12);
  const auto* sphere = std::get_if<primitives::SphereModel>(&instances[2].model);
  ASSERT_NE(sphere, nullptr);
  EXPECT_DOUBLE_EQ(sphere->radius, 0.05);
  const auto* line = std::get_if<primitives::LineModel>(&instances[3].model);
  ASSERT_NE(line, nullptr);
  EXPECT_DOUBLE_EQ(line->length, 0.5);
  EXPECT_EQ(line->direction, primitives::Vec3d(0, 1, 0));
  EXPECT_DOUBLE_EQ(instances[3].rms, 0.004);
}

// --objects (with --tabletop) writes the summary's table and objects as the core's JSON (read
// back with its parser) and every point's object id as the `object` field; without --tabletop it
// is a usage error.
TEST(ClientCli, ObjectsGoToTheirJsonFileAndTheObjectField) {
  FakeServer server;
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  const std::string base = cli() + " --server " + server.address() + " label " +
                           dir.file("scan.pcd") + " -o " + dir.file("out.pcd") + " --objects " +
                           dir.file("objects.json");
  const auto refused = test::run_command(base);
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("--tabletop"), std::string::npos) << refused.output;

  const auto r = test::run_command(base + " --tabletop --chunk-points 64");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const tabletop::TabletopObjects objects =
      tabletop::parse_objects_json(read_text(dir.file("objects.json")));
  ASSERT_TRUE(objects.table);
  EXPECT_EQ(objects.table->plane, Eigen::Vector4f(0, 0, 1, -0.3f));
  EXPECT_EQ(objects.table->hull.size(), 4u);
  EXPECT_EQ(objects.table->points, 60u);  // x = 1: every fifth of 300 points
  EXPECT_EQ(objects.table->primitive_ids, std::vector<std::uint32_t>{0});
  ASSERT_EQ(objects.objects.size(), 2u);
  for (std::uint32_t id = 1; id <= 2; ++id) {
    const tabletop::TabletopObject& o = objects.objects[id - 1];
    EXPECT_EQ(o.id, id);
    EXPECT_EQ(o.points, 60u);
    EXPECT_EQ(o.centroid, Eigen::Vector3d(id + 1, 1.5, 0.35));
    EXPECT_EQ(o.bounds_min, Eigen::Vector3d(id + 0.5, 0.0, 0.3));
    EXPECT_EQ(o.bounds_max, Eigen::Vector3d(id + 1.5, 3.0, 0.4));
    EXPECT_DOUBLE_EQ(o.height, 0.1 * id);
    EXPECT_EQ(o.primitive_ids, std::vector<std::uint32_t>{id});
  }
  const PointCloud out = read_cloud(dir.file("out.pcd"));
  const FloatField* field = out.find_field("object");
  ASSERT_NE(field, nullptr);
  ASSERT_EQ(field->values.size(), out.size());
  for (std::size_t i = 0; i < out.size(); ++i) {  // label i % 5: 1 table, 2, 3 objects, else -1
    const int label = int(i % 5);
    const float want = label == 1 ? 0.0f : label == 2 ? 1.0f : label == 3 ? 2.0f : -1.0f;
    ASSERT_EQ(field->values[i], want) << i;
  }
}

// A camera frame as PCL's office1.pcd has it: organised, its points in the optical frame (a
// table 0.4 m below the sensor, 2 m to its right so the fake labels it 2), a VIEWPOINT rotated
// 90 degrees about x, and every fifth point NaN (no return).
void write_rotated_viewpoint_frame(const std::string& path) {
  PointCloud frame;
  frame.width = 50, frame.height = 40;
  for (int r = 0; r < 40; ++r)
    for (int c = 0; c < 50; ++c)
      frame.xyz.emplace_back(1.6f + 0.8f * float(c) / 49, 0.4f, 0.8f + 0.8f * float(r) / 39);
  for (std::size_t i = 0; i < frame.size(); i += 5)
    frame.xyz[i] = Vec3f::Constant(std::numeric_limits<float>::quiet_NaN());
  frame.viewpoint.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(0.5f * M_PI, Vec3f::UnitX()));
  write_cloud(path, frame);
}

// Pixels of the plot area (right of the legend and below the title) that are not background.
std::size_t drawn_pixels(const test::Decoded& png) {
  std::size_t n = 0;
  for (int y = 40; y < png.height; ++y)
    for (int x = 400; x < png.width; ++x) n += png.at(x, y) != 0xFFFFFFu;
  return n;
}

TEST(ClientCli, PngOfAFrameWithARotatedViewpointShowsThePoints) {
  FakeServer server;
  test::TempDir dir;
  write_rotated_viewpoint_frame(dir.file("office.pcd"));
  ASSERT_NE(read_cloud(dir.file("office.pcd")).viewpoint.orientation.w(), 1.0f);
  const auto r =
      test::run_command(cli() + " --server " + server.address() + " label " +
                        dir.file("office.pcd") + " -o " + dir.file("out.pcd") + " --png");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GT(drawn_pixels(test::decode_png(dir.file("out.png"))), 3000u);  // blank: 0
}

// The summary line names the points without a position as the picture's legend does, not as
// "unknown" (the class the server gives them).
TEST(ClientCli, TheSummaryLineSeparatesNanPointsFromUnknownOnesAsThePictureDoes) {
  FakeServer server;
  test::TempDir dir;
  write_rotated_viewpoint_frame(dir.file("office.pcd"));
  const auto r = test::run_command(cli() + " --server " + server.address() + " label " +
                                   dir.file("office.pcd") + " -o " + dir.file("out.pcd"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no point (NaN) 20%"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("unknown"), std::string::npos) << r.output;

  PointCloud labeled;  // and the NaN share is named even when it is not among the largest
  labeled.resize_unorganized(100);
  labeled.labels.resize(100);
  for (std::size_t i = 0; i < 100; ++i) {
    labeled.xyz[i] = Vec3f(1, 2, 3);
    labeled.labels[i] = std::uint32_t(i % 4 + 1);
  }
  labeled.xyz[0] = Vec3f::Constant(std::numeric_limits<float>::quiet_NaN());
  const std::string line = client::tools::label_histogram(labeled, 2);
  EXPECT_NE(line.find("no point (NaN) 1%"), std::string::npos) << line;
  EXPECT_EQ(std::count(line.begin(), line.end(), '%'), 3) << line;
}

// A scan the fake server labels into pictures.
class ClientCliPng : public ::testing::Test {
 protected:
  void SetUp() override { write_scan(dir.file("scan.pcd")); }
  // `primlabel label SCAN --png -o`: the output path and further flags follow.
  std::string png_label_command() const {
    return cli() + " -q --server " + server.address() + " label " + dir.file("scan.pcd") +
           " --png -o ";
  }

  FakeServer server;
  test::TempDir dir;
};

TEST_F(ClientCliPng, PngViewIsChosenByView) {
  const std::string base = png_label_command();
  ASSERT_EQ(test::run_command(base + dir.file("auto.pcd")).exit_code, 0);
  auto r = test::run_command(base + dir.file("top.pcd") + " --view top");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const test::Decoded oblique = test::decode_png(dir.file("auto.png"));
  const test::Decoded top = test::decode_png(dir.file("top.png"));
  EXPECT_NE(oblique.height, top.height);  // a flat strip seen from above is less tall
  r = test::run_command(base + dir.file("x.pcd") + " --view sideways");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--view"), std::string::npos) << r.output;
}

// --tabletop --png draws the table's hull and each object's box with its id over the points,
// without --objects too (which alone adds the JSON and the `object` field).
TEST_F(ClientCliPng, TabletopPngDrawsTheObjects) {
  const std::string base = png_label_command();
  ASSERT_EQ(test::run_command(base + dir.file("plain.pcd")).exit_code, 0);
  const auto r = test::run_command(base + dir.file("table.pcd") + " --tabletop");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const test::Decoded plain = test::decode_png(dir.file("plain.png"));
  const test::Decoded table = test::decode_png(dir.file("table.png"));
  ASSERT_EQ(plain.rgb.size(), table.rgb.size());
  EXPECT_GT(table.pixels_differing_from(plain), 1000u);
  const auto black = [](const test::Decoded& png) {
    return png.count(0x000000, 0, 0, png.width, png.height);
  };
  EXPECT_GT(black(table), black(plain) + 500) << black(table) << " vs " << black(plain);
  EXPECT_EQ(read_cloud(dir.file("table.pcd")).find_field("object"), nullptr);
  ASSERT_EQ(server.service.options.size(), 2u);
  EXPECT_TRUE(server.service.options[1].return_objects());
}

// A folder is its .pcd and .ply files, by name: not its subfolders, hidden files, other files or
// the outputs of an earlier run; the outputs go into -o as for several files.
TEST(ClientCli, AFolderLabelsEveryScanInItByName) {
  FakeServer server;
  test::TempDir dir;
  std::filesystem::create_directories(dir.file("in/sub"));
  write_scan(dir.file("in/b.pcd"));
  write_scan(dir.file("in/a.ply"));
  write_scan(dir.file("in/sub/c.pcd"));
  write_scan(dir.file("in/.hidden.pcd"));
  write_scan(dir.file("in/old_labeled.pcd"));
  { std::ofstream(dir.file("in/notes.txt")) << "not a scan\n"; }
  auto r = test::run_command(cli() + " --server " + server.address() + " label " + dir.file("in") +
                             " -o " + dir.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(server.service.scan_ids, (std::vector<std::string>{"a", "b"}));
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/a_labeled.pcd")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/b_labeled.pcd")));
  // A folder with one scan still writes into the -o directory.
  std::filesystem::create_directories(dir.file("one"));
  write_scan(dir.file("one/only.pcd"));
  r = test::run_command(cli() + " -q --server " + server.address() + " label " + dir.file("one") +
                        " -o " + dir.file("out1"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("out1/only_labeled.pcd")));
  // A folder without a scan is said, and is a file error.
  std::filesystem::create_directories(dir.file("empty"));
  r = test::run_command(cli() + " -q --server " + server.address() + " label " + dir.file("empty"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("empty: no .pcd or .ply file in the folder"), std::string::npos)
      << r.output;
}

// The server's work on a sent scan shows as progress (stderr is not a terminal here: one line
// after 2 s, the next at 7 s), not as silence; --quiet keeps it quiet.
TEST(ClientCli, WaitingForTheServerShowsProgress) {
  FakeServer server;
  server.service.delay_ms = 3500;
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  const std::string args = " --server " + server.address() + " label " + dir.file("scan.pcd") +
                           " -o " + dir.file("out.pcd");
  auto r = test::run_command(cli() + args);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string line = dir.file("scan.pcd") + ": waiting for the server: 2 s\n";
  EXPECT_NE(r.output.find(line), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("waiting for the server: 7 s"), std::string::npos) << r.output;
  r = test::run_command(cli() + " -q" + args);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("waiting"), std::string::npos) << r.output;
  r = test::run_command(cli() + args + " --unary");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(line), std::string::npos) << r.output;
  // On a terminal (util-linux `script` gives one) the line is redrawn in place, then ended.
  if (test::run_command("command -v script").exit_code != 0) GTEST_SKIP() << "no script(1)";
  r = test::run_command("script -qec '" + cli() + args + "' /dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\r" + dir.file("scan.pcd") + ": waiting for the server: "),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find(" s\r\n" + dir.file("scan.pcd") + ": 300 points"), std::string::npos)
      << r.output;
}

TEST(ClientCli, LabeledFilesDescribeThemselvesInTheirHeader) {
  FakeServer server;
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  for (const char* name : {"out.pcd", "out.ply"}) {
    const auto r = test::run_command(cli() + " -q --server " + server.address() + " label " +
                                     dir.file("scan.pcd") + " -o " + dir.file(name) +
                                     " --descriptors --probabilities");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const CloudTags tags = read_cloud_tags(dir.file(name));
    EXPECT_EQ(tags.at("model"), "fake") << name;
    EXPECT_EQ(tags.at("model_version"), "1") << name;
    EXPECT_EQ(tags.at("descriptor"), "fpfh_paper") << name;
    // The label field's class map is the taxonomy's, readable back as a ClassMap.
    const ClassMap map = class_map_from_tag(tags.at("classes"));
    EXPECT_EQ(map.to_text(), ClassMap::taxonomy().to_text()) << name;
    // One id:name per probability column, in the columns' order.
    const std::string& columns = tags.at("probability_columns");
    EXPECT_EQ(std::count(columns.begin(), columns.end(), ':'), 3) << columns;
    EXPECT_EQ(read_cloud(dir.file(name)).labels.size(), 300u);
  }
}

// Readers that drop header comments (PCL, Open3D) get the same facts from out.classes.json.
TEST(ClientCli, LabeledFilesHaveTheirClassesInAJsonFileBeside) {
  FakeServer server;
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  for (const char* name : {"out.pcd", "out.ply"}) {
    std::filesystem::remove(dir.file("out.classes.json"));
    const auto r = test::run_command(cli() + " -q --server " + server.address() + " label " +
                                     dir.file("scan.pcd") + " -o " + dir.file(name) +
                                     " --descriptors --probabilities");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(dir.file("out.classes.json"));
    ASSERT_TRUE(in.good()) << name;
    const nlohmann::json meta = nlohmann::json::parse(in);
    EXPECT_EQ(meta.at("model"), "fake");
    EXPECT_EQ(meta.at("label_field"), "label");
    // Every class of the taxonomy, id 0 included, as the label field holds them.
    const auto& classes = meta.at("classes");
    ASSERT_EQ(classes.size(), ClassMap::taxonomy().entries().size());
    for (std::size_t k = 0; k < classes.size(); ++k) {
      EXPECT_EQ(classes[k].at("id"), ClassMap::taxonomy().entries()[k].id);
      EXPECT_EQ(classes[k].at("name"), ClassMap::taxonomy().entries()[k].name);
    }
    // Each probability field it names is a column of the file, with the class the server gave.
    std::ifstream file(dir.file(name), std::ios::binary);
    const std::string header((std::istreambuf_iterator<char>(file)), {});
    const auto& probabilities = meta.at("probability_fields");
    ASSERT_EQ(probabilities.size(), 3u);
    EXPECT_EQ(probabilities[1].at("field"), "prob_class_1");
    EXPECT_EQ(probabilities[1].at("name"), "class-1");
    for (const auto& p : probabilities) {
      const std::string field = p.at("field").get<std::string>();
      const bool pcd = std::string(name).ends_with(".pcd");
      const std::string column = pcd ? " " + field + " " : "property float " + field + "\n";
      EXPECT_NE(header.find(column), std::string::npos) << field << " in " << name;
    }
    const auto& descriptor = meta.at("descriptor");
    EXPECT_EQ(descriptor.at("field"), "fpfh_paper");
    EXPECT_EQ(descriptor.at("values"), 33);
    ASSERT_EQ(descriptor.at("columns").size(), 33u);
    EXPECT_EQ(descriptor.at("columns")[32], "fpfh_paper_32");
  }
}

TEST(ClientCli, SeveralFilesGoToTheOutputDirectory) {
  FakeServer server;
  test::TempDir dir;
  write_scan(dir.file("a.pcd"));
  write_scan(dir.file("b.ply"), 40);
  const auto r =
      test::run_command(cli() + " -q --server " + server.address() + " label " + dir.file("a.pcd") +
                        " " + dir.file("b.ply") + " -o " + dir.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");
  EXPECT_EQ(read_cloud(dir.file("out/a_labeled.pcd")).labels.size(), 300u);
  EXPECT_EQ(read_cloud(dir.file("out/b_labeled.pcd")).labels.size(), 40u);
}

// Several inputs write one file each into a directory: a target naming a file (by its extension,
// or an existing file) is refused before anything is sent, instead of becoming a directory.
TEST(ClientCli, SeveralFilesAndAFileAsOutputIsAUsageError) {
  FakeServer server;
  test::TempDir dir;
  write_scan(dir.file("a.pcd"));
  write_scan(dir.file("b.pcd"));
  std::ofstream(dir.file("existing")) << "x\n";
  for (const std::string& target :
       {"-o " + dir.file("single.pcd"), "-o " + dir.file("SINGLE.PLY"),
        "-o " + dir.file("existing"), "--primitives " + dir.file("p.json")}) {
    const auto r = test::run_command(cli() + " --server " + server.address() + " label " +
                                     dir.file("a.pcd") + " " + dir.file("b.pcd") + " " + target);
    EXPECT_EQ(r.exit_code, 2) << target << ": " << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
    EXPECT_NE(r.output.find("2 inputs write one file each into a directory"), std::string::npos)
        << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("single.pcd")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("p.json")));
  EXPECT_EQ(server.service.label_calls.load(), 0);
}

TEST(ClientCli, MissingOrBrokenInputExitsOne) {
  FakeServer server;
  test::TempDir dir;
  std::ofstream(dir.file("broken.pcd")) << "not a pcd\n";
  for (const std::string& input : {dir.file("missing.pcd"), dir.file("broken.pcd")}) {
    const auto r = test::run_command(cli() + " --server " + server.address() + " label " + input);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
    EXPECT_NE(r.output.find(input), std::string::npos) << r.output;
  }
  const auto r = test::run_command(cli() + " --server " + server.address() + " --token-file " +
                                   dir.file("none") + " health");
  EXPECT_EQ(r.exit_code, 1) << r.output;
}

// A cloud of NaNs (a depth frame with the lens covered) or no points at all: nothing was
// labeled, so not exit 0 and "unknown 100%", but exit 1 and why; the other inputs go on.
TEST(ClientCli, ACloudWithNoFinitePointExitsOneSayingSo) {
  FakeServer server;
  test::TempDir dir;
  write_cloud(dir.file("blind.pcd"), test::nan_cloud(50));
  write_scan(dir.file("scan.pcd"));
  const auto r = test::run_command(cli() + " --server " + server.address() + " label " +
                                   dir.file("blind.pcd") + " " + dir.file("scan.pcd") + " -o " +
                                   dir.file("out"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("blind.pcd: no point has finite coordinates (50 points)"),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/scan_labeled.pcd")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("out/blind_labeled.pcd")));
}

// --units scales what is sent (points and viewpoint) to metres; the file written back keeps the
// input's own coordinates. A unit it does not know is a usage error.
TEST(ClientCli, UnitsScaleThePointsSentAndTheOutputKeepsTheInputs) {
  FakeServer server;
  test::TempDir dir;
  PointCloud scan;
  scan.resize_unorganized(100);
  for (std::size_t i = 0; i < 100; ++i) scan.xyz[i] = Vec3f(float(i), 500.0f, 1200.0f);
  scan.viewpoint.origin = Vec3f(0.0f, 0.0f, 100.0f);
  write_cloud(dir.file("mm.pcd"), scan);
  const std::string base = cli() + " --server " + server.address() + " label " +
                           dir.file("mm.pcd") + " -o " + dir.file("out.pcd");
  for (const auto& [flag, scale] :
       {std::pair{"mm", 0.001f}, std::pair{"CM", 0.01f}, std::pair{"m", 1.0f}}) {
    SCOPED_TRACE(flag);
    const auto r = test::run_command(base + " --units " + flag);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::lock_guard lock(server.service.mutex);
    EXPECT_TRUE(server.service.first_points.back().isApprox(scan.xyz[0] * scale));
    EXPECT_TRUE(server.service.viewpoints.back().isApprox(scan.viewpoint.origin * scale));
    EXPECT_EQ(read_cloud(dir.file("out.pcd")).xyz[99], scan.xyz[99]);
  }
  const auto bad = test::run_command(base + " --units inch");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--units"), std::string::npos) << bad.output;
}

TEST(ClientCli, UnreachableServerExitsThree) {
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  const std::string server = " --retries 2 --server " + dead_address();
  for (const std::string& command : {std::string(" health"), " label " + dir.file("scan.pcd")}) {
    const auto r = test::run_command(cli() + server + command);
    EXPECT_EQ(r.exit_code, 3) << command << ": " << r.output;
    EXPECT_NE(r.output.find("UNAVAILABLE"), std::string::npos) << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  }
}

TEST(ClientCli, RejectedRequestExitsFourWithTheStatus) {
  FakeServer server;
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  auto r = test::run_command(cli() + " --server " + server.address() + " label --model nope " +
                             dir.file("scan.pcd"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("NOT_FOUND"), std::string::npos) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  r = test::run_command(cli() + " --server " + server.address() + " info nope");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  server.service.required_token = "tok";
  r = test::run_command(cli() + " --server " + server.address() + " label " + dir.file("scan.pcd"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("UNAUTHENTICATED"), std::string::npos) << r.output;
  std::ofstream(dir.file("token")) << "tok\n";
  r = test::run_command(cli() + " --server " + server.address() + " --token-file " +
                        dir.file("token") + " label " + dir.file("scan.pcd"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(ClientCli, ServerAddressWithoutAPortGetsTheServersDefaultPort) {
  using client::tools::server_address_with_port;
  EXPECT_EQ(client::tools::kDefaultServerPort, 50051);  // primlabel-server --listen's default
  EXPECT_EQ(server_address_with_port("labeler"), "labeler:50051");
  EXPECT_EQ(server_address_with_port("127.0.0.1"), "127.0.0.1:50051");
  EXPECT_EQ(server_address_with_port("labeler:7000"), "labeler:7000");
  EXPECT_EQ(server_address_with_port("[::1]"), "[::1]:50051");
  EXPECT_EQ(server_address_with_port("[::1]:7000"), "[::1]:7000");
  EXPECT_EQ(server_address_with_port("::1"), "[::1]:50051");
  EXPECT_EQ(server_address_with_port("dns:///labeler:7000"), "dns:///labeler:7000");
  EXPECT_EQ(server_address_with_port("unix:/run/primlabel.sock"), "unix:/run/primlabel.sock");
  for (const char* bad :
       {"", "labeler:", "labeler:0", "labeler:x", "labeler:70000", ":50051", "[::1", "[::1]x",
        "a b", "labeler:-1", "http://127.0.0.1:50731", "grpc://labeler", "labeler:7000:1"})
    EXPECT_THROW(server_address_with_port(bad), std::invalid_argument) << bad;
}

TEST(ClientCli, AMistypedCommandIsNamedWithTheNearestOne) {
  auto r = test::run_command(cli() + " lable x.pcd");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("unknown command 'lable' (did you mean 'label'?)"), std::string::npos)
      << r.output;
  r = test::run_command(cli() + " frobnicate");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(
      r.output.find("unknown command 'frobnicate'; the commands: health, models, info, label"),
      std::string::npos)
      << r.output;
}

TEST(ClientCli, ABadServerAddressIsAUsageErrorNamingIt) {
  for (const std::string address :
       {"labeler:", "labeler:0", "labeler:http", "http://127.0.0.1:50731"}) {
    const auto r = test::run_command(cli() + " --server " + address + " health");
    EXPECT_EQ(r.exit_code, 2) << address << ": " << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
    EXPECT_NE(r.output.find("'" + address + "'"), std::string::npos) << r.output;
  }
  auto r = test::run_command("PRIMLABEL_SERVER=labeler: " + cli() + " health");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // A URL says what to give instead, at once (no connection attempts).
  r = test::run_command(cli() + " --server http://127.0.0.1:50731/ health");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("give HOST:PORT (e.g. '127.0.0.1:50731')"), std::string::npos)
      << r.output;
}

// $PRIMLABEL_SERVER stands in for --server; the flag wins over it.
TEST(ClientCli, PrimlabelServerFromTheEnvironmentAndTheFlagWins) {
  FakeServer server;
  auto r = test::run_command("PRIMLABEL_SERVER=" + server.address() + " " + cli() + " health");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "SERVING\n");
  r = test::run_command("PRIMLABEL_SERVER=" + dead_address() + " " + cli() + " --server " +
                        server.address() + " health");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = test::run_command("PRIMLABEL_SERVER=" + dead_address() + " " + cli() + " --retries 1 health");
  EXPECT_EQ(r.exit_code, 3) << r.output;  // the environment is used when the flag is absent
  r = test::run_command("PRIMLABEL_SERVER=" + server.address() + " " + cli() + " --help");
  EXPECT_NE(r.output.find("PRIMLABEL_SERVER"), std::string::npos) << r.output;
}

TEST(ClientCli, APassedDeadlineNamesTheDeadlineFlag) {
  FakeServer server;
  server.service.delay_ms = 5000;
  test::TempDir dir;
  write_scan(dir.file("scan.pcd"));
  const auto r = test::run_command(cli() + " --deadline 0.3 --server " + server.address() +
                                   " label " + dir.file("scan.pcd"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("DEADLINE_EXCEEDED"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--deadline is 0.3 s"), std::string::npos) << r.output;
}

TEST(ClientCli, InfoPrintsTheCreationDateAndNaForUndefinedScores) {
  FakeServer server;
  const auto r = test::run_command(cli() + " --server " + server.address() + " info fake");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("created    2026-01-02 03:04:05 UTC ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" ago) by fake-trainer"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("1767323045"), std::string::npos) << r.output;  // no raw milliseconds
  EXPECT_NE(r.output.find("class-0            F1 0.500"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("class-1            F1 n/a"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("class-2            F1 n/a"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("nan"), std::string::npos) << r.output;
}

TEST(ClientCli, HumanUnitsForTimesAndScores) {
  using namespace client::tools;
  const std::int64_t t = 1767323045123;  // 2026-01-02 03:04:05.123 UTC
  EXPECT_EQ(describe_unix_ms(t, t + 45'000), "2026-01-02 03:04:05 UTC (45 s ago)");
  EXPECT_EQ(describe_unix_ms(t, t + 3 * 60'000 + 5'000), "2026-01-02 03:04:05 UTC (3 min ago)");
  EXPECT_EQ(describe_unix_ms(t, t + 5 * 3'600'000LL), "2026-01-02 03:04:05 UTC (5 h ago)");
  EXPECT_EQ(describe_unix_ms(t, t + 3 * 86'400'000LL), "2026-01-02 03:04:05 UTC (3 days ago)");
  EXPECT_EQ(describe_unix_ms(t, t - 1000), "2026-01-02 03:04:05 UTC (in the future)");
  EXPECT_EQ(describe_unix_ms(0, t), "unknown");
  EXPECT_EQ(describe_age_ms(-5000), "0 s");
  EXPECT_EQ(score_or_na(0.98765), "0.988");
  EXPECT_EQ(score_or_na(0.98765, 4), "0.9877");
  EXPECT_EQ(score_or_na(std::nan("")), "n/a");
  EXPECT_EQ(score_or_na(std::numeric_limits<double>::infinity()), "n/a");
}

}  // namespace
}  // namespace primlabel
