// primlabel-research as a user runs it: each subcommand (table1, fig4, mosd-report, write-truth,
// truth-check, calibrate-kinect) on a small input, exit codes 0 / 1 / 2 and one-line errors.
// The mOSD subcommands get a synthetic Kinect frame with mOSD's segment labels (primlabel-synth
// --segment-labels), so they run without ../shared.

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>

#include "png_decode.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/model/label_model.hpp"
#include "random_label_model.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

namespace fs = std::filesystem;

using Result = test::CommandResult;

Result run(const std::string& command) { return test::run_command(command); }

std::string research() { return test::binary("primlabel-research"); }

class ResearchCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs the cases in parallel processes.
    dir_ = new test::TempDir;
    // An all-zero node-only model with small radii: fast on a 640x480 frame, labels all plane.
    save_model(model_path(), testing::zero_node_model(0.008f, 0.012f));
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string model_path() { return dir_->file("zero.plm"); }
  static std::string file(const std::string& name) { return dir_->file(name); }

  // A held-out synthetic Kinect frame labeled as mOSD labels its scenes (1 table, 10 (k + 1)
  // object k), alone in its folder (calibrate-kinect takes a folder). Made on first use.
  static std::string mosd_like_scene() {
    const std::string path = file("scenes/frame.pcd");
    if (fs::exists(path)) return path;
    fs::create_directories(file("scenes"));
    const Result r =
        run(test::binary("primlabel-synth") +
            " --scene table --sensor kinect --seed 3000 --segment-labels -q -o " + path);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return path;
  }

  static inline test::TempDir* dir_ = nullptr;
};

TEST_F(ResearchCli, NeedsAKnownSubcommand) {
  for (const std::string& command :
       {research(), research() + " table2", research() + " --table1"}) {
    const Result r = run(command);
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << command << "\n" << r.output;
  }
}

TEST_F(ResearchCli, EverySubcommandAnswersHelp) {
  for (const char* subcommand :
       {"table1", "fig4", "mosd-report", "write-truth", "truth-check", "calibrate-kinect"}) {
    const Result r = run(research() + " " + subcommand + " --help");
    EXPECT_EQ(r.exit_code, 0) << subcommand << "\n" << r.output;
    EXPECT_NE(r.output.find(std::string("primlabel-research ") + subcommand), std::string::npos)
        << r.output;
  }
}

// Bad node knots are refused before any scene is described: one line, no progress, exit 2.
TEST_F(ResearchCli, Table1RefusesBadKnotsBeforeAnyScene) {
  for (const std::string& command :
       {research() + " table1 --node-knots 0,0.5,0.2",
        research() + " table1 --node-basis linear --node-knots 0,1",
        research() + " table1 --train-scenes 0", research() + " table1 --table1-train 2"}) {
    const Result r = run(command);
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << command << "\n" << r.output;
    EXPECT_EQ(r.output.rfind("primlabel-research table1: usage error: ", 0), 0u) << r.output;
  }
}

// One training and one test scene, FPFH only, no SVM: the CRF and node-only rows (~6 s).
TEST_F(ResearchCli, Table1OnOneSceneEachPrintsAJsonLinePerRow) {
  const Result r = run(research() +
                       " table1 --train-scenes 1 --test-scenes 1 --no-pfh --no-svm --json -q "
                       "--threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(test::count_lines(r.output), 2) << r.output;
  std::istringstream rows(r.output);
  for (const char* method : {"crf", "node"}) {
    std::string text;
    std::getline(rows, text);
    const json::Json row = json::Json::parse(text);
    EXPECT_EQ(row["method"], method) << text;
    EXPECT_EQ(row["descriptor"], "fpfh") << text;
    EXPECT_GT(row["accuracy"].get<double>(), 0.5) << text;
  }
}

TEST_F(ResearchCli, Fig4WritesItsFilesAndOneJsonLine) {
  const std::string out = file("fig4");
  const Result r = run(research() + " fig4 " + out + " --scenes 1 --json -q --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  const json::Json line = json::Json::parse(r.output);
  ASSERT_TRUE(line.contains("hik")) << r.output;
  EXPECT_EQ(line["hik"].size(), line["classes"].size());
  for (const char* name :
       {"fig4_signatures.csv", "fig4_hik.csv", "fig4_signatures.png", "fig4_hik.png"})
    EXPECT_TRUE(fs::exists(fs::path(out) / name)) << name;
  EXPECT_EQ(run(research() + " fig4 --scenes 1").exit_code, 2);  // no DIR
}

TEST_F(ResearchCli, MosdReportScoresASceneAndWritesItsTruth) {
  const std::string scene = mosd_like_scene();
  const std::string out = file("report"), truth = file("report_truth");
  const Result r =
      run(research() + " mosd-report " + out + " --model " + model_path() +
          " --object-truth --write-truth " + truth + " --json -q --threads 2 " + scene);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json::Json report = json::Json::parse(r.output);
  EXPECT_GT(report["table_points"].get<std::uint64_t>(), 10000u) << r.output;
  EXPECT_GT(report["plane_share"].get<double>(), 0.5) << r.output;  // the zero model: plane
  EXPECT_TRUE(report.contains("object_truth")) << r.output;
  EXPECT_TRUE(fs::exists(fs::path(out) / "mosd_report.json"));
  EXPECT_GT(test::decode_png((fs::path(out) / "frame_labels.png").string()).width, 0);
  EXPECT_TRUE(fs::exists(fs::path(truth) / "frame_truth.pcd"));
  // The model and the scenes are needed.
  for (const std::string& command : {research() + " mosd-report " + out + " " + scene,
                                     research() + " mosd-report " + out + " --model m.plm"}) {
    const Result bad = run(command);
    EXPECT_EQ(bad.exit_code, 2) << command << "\n" << bad.output;
    EXPECT_EQ(test::count_lines(bad.output), 1) << command << "\n" << bad.output;
  }
}

// The fitted truth alone: a labeled cloud with a segment field per scene, and truth_fits.json.
TEST_F(ResearchCli, WriteTruthWritesTheTruthOfAScene) {
  const std::string scene = mosd_like_scene();
  const std::string truth = file("truth");
  const Result r = run(research() + " write-truth " + truth + " --threads 2 " + scene);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(" segments: "), std::string::npos) << r.output;
  const PointCloud labeled = load_labeled_cloud((fs::path(truth) / "frame_truth.pcd").string());
  EXPECT_NE(labeled.find_field("segment"), nullptr);
  EXPECT_TRUE(fs::exists(fs::path(truth) / "truth_fits.json"));
  const Result no_scenes = run(research() + " write-truth " + truth);
  EXPECT_EQ(no_scenes.exit_code, 2) << no_scenes.output;
  EXPECT_EQ(test::count_lines(no_scenes.output), 1) << no_scenes.output;
}

TEST_F(ResearchCli, TruthCheckOnOneScenePrintsItsScores) {
  const Result r = run(research() + " truth-check 1 --json --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json::Json check = json::Json::parse(r.output);
  EXPECT_GT(check["all_points"].get<std::uint64_t>(), 0u) << r.output;
  for (const std::string& command : {research() + " truth-check", research() + " truth-check 0"})
    EXPECT_EQ(run(command).exit_code, 2) << command;
}

TEST_F(ResearchCli, CalibrateKinectMeasuresTheScenesOfAFolder) {
  const std::string scene = mosd_like_scene();
  const std::string saved = file("calibration.json");
  const Result r = run(research() + " calibrate-kinect " + fs::path(scene).parent_path().string() +
                       " --calibration-json " + saved + " --json -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json::Json calibration = json::Json::parse(r.output);
  EXPECT_EQ(calibration["frames"].get<int>(), 1) << r.output;
  EXPECT_TRUE(fs::exists(saved));
}

TEST_F(ResearchCli, CalibrateKinectWithoutScenesFailsWithOneLine) {
  const Result r = run(research() + " calibrate-kinect -q /nonexistent/mosd");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  EXPECT_EQ(r.output.rfind("primlabel-research calibrate-kinect: error: ", 0), 0u) << r.output;
}

}  // namespace
}  // namespace primlabel
