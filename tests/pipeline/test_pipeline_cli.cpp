// primlabel-train and primlabel-eval as a user runs them: a model trained by the tool loads and
// labels, exit codes 0 / 1 / 2 and one-line errors (primlabel-research: tests/research).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <utility>
#include <vector>

#include "png_decode.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/features.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/primitives/primitives_json.hpp"
#include "primlabel/synth/generate.hpp"
#include "primlabel/tabletop/objects_json.hpp"
#include "random_label_model.hpp"
#include "tabletop_objects_scene.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

using Result = test::CommandResult;

Result run(const std::string& command) { return test::run_command(command); }

class PipelineCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs the cases in parallel processes.
    dir_ = new test::TempDir;
    // An all-zero node-only model: loads and labels instantly (the trained one is tested below).
    save_model(zero_model_path(), testing::zero_node_model());
    synth::GenerateOptions options;
    options.seed = synth::set_seed(synth::SceneSet::kTest, 0);
    const synth::Generated scene = synth::generate(options);
    write_tagged_cloud(scene_path(), scene.cloud, scene.tags);
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string model_path() { return dir_->file("model.plm"); }
  static std::string zero_model_path() { return dir_->file("zero.plm"); }
  static std::string scene_path() { return dir_->file("scene.pcd"); }
  static std::string eval() { return test::binary("primlabel-eval"); }
  // primlabel-train on one synthetic scene without validation: fast enough for every case.
  static Result train_on_one_scene(const std::string& flags, const std::string& out) {
    return run(test::binary("primlabel-train") + " --synth-train 1 --synth-val 0 --threads 2 -q " +
               flags + " -o " + out);
  }

  static inline test::TempDir* dir_ = nullptr;
};

// A node-only model from one training scene: fast, and enough to check the tools.
TEST_F(PipelineCli, TrainedModelLoadsAndLabelsWithJsonScores) {
  const Result trained = train_on_one_scene("--kind node --iterations 30", model_path());
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  const Result r = run(eval() + " --model " + model_path() + " --json -q " + scene_path());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"accuracy\":0."), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"plane\":{\"precision\""), std::string::npos) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  const LabelModel model = load_model(model_path());
  EXPECT_EQ(model.kind, ModelKind::kNodeOnly);
  EXPECT_EQ(model.training.scenes, 1u);
  EXPECT_FALSE(model.class_ids().empty());
}

TEST_F(PipelineCli, SvmModelTrainsAndEvaluates) {
  const std::string svm = dir_->file("svm.plm");
  const Result trained = train_on_one_scene("--kind svm --svm-max-points 1000", svm);
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  EXPECT_EQ(load_model(svm).kind, ModelKind::kSvm);
  const Result r = run(eval() + " --model " + svm + " --json -q --threads 2 " + scene_path());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"accuracy\":0."), std::string::npos) << r.output;
}

TEST_F(PipelineCli, WritesPredictedLabelsAndHistogramWithoutTruth) {
  const std::string out = dir_->file("labeled.pcd");
  const Result r = run(eval() + " --model " + zero_model_path() + " --no-truth -q --out " + out +
                       " " + scene_path());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("predicted labels"), std::string::npos) << r.output;
  const PointCloud labeled = load_labeled_cloud(out);
  EXPECT_TRUE(labeled.has_labels());
}

// The all-zero model labels every point plane, so the largest instance is the table top, the
// plane z = 0 of the synthetic scene.
TEST_F(PipelineCli, WritesPrimitivesAsJson) {
  const std::string out = dir_->file("primitives.json");
  const Result r = run(eval() + " --model " + zero_model_path() + " --no-truth -q --primitives " +
                       out + " " + scene_path());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::vector<primitives::Primitive> read = primitives::parse_primitives_json(text);
  ASSERT_FALSE(read.empty()) << text.substr(0, 400);
  const primitives::Primitive& table = read.front();
  ASSERT_EQ(table.kind(), primitives::PrimitiveKind::kPlane);
  EXPECT_EQ(table.class_id, class_id(PrimitiveClass::kPlane));
  const auto& plane = std::get<primitives::PlaneModel>(table.model);
  EXPECT_GT(std::abs(plane.normal.z()), 0.9999);
  EXPECT_LT(std::abs(plane.offset), 0.001);
  EXPECT_LT(std::abs(plane.center.z()), 0.001);
  EXPECT_GT(table.inliers, table.points / 2);
  EXPECT_LT(table.rms, 0.001);
  // Usage: one input file only.
  EXPECT_EQ(run(eval() + " --model " + zero_model_path() + " -q --primitives " + out + " " +
                scene_path() + " " + scene_path())
                .exit_code,
            2);
}

// --objects with --tabletop-only: the table and the two boxes and the can of the synthetic
// table, as the JSON the CLI writes too (read back by the core's parser).
TEST_F(PipelineCli, WritesTableTopObjectsAsJson) {
  const std::string scene = dir_->file("objects_scene.pcd");
  write_cloud(scene, testing::objects_scene(0.005f).cloud);
  const std::string out = dir_->file("objects.json");
  const Result r = run(eval() + " --model " + zero_model_path() +
                       " --no-truth -q --tabletop-only --primitives " +
                       dir_->file("objects_primitives.json") + " --objects " + out + " " + scene);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const tabletop::TabletopObjects read = tabletop::parse_objects_json(text);
  ASSERT_TRUE(read.table) << text.substr(0, 400);
  EXPECT_GT(std::abs(read.table->plane[2]), 0.999f);
  ASSERT_EQ(read.objects.size(), 3u) << text.substr(0, 400);
  std::vector<double> heights;
  for (const tabletop::TabletopObject& o : read.objects) heights.push_back(o.height);
  std::sort(heights.begin(), heights.end());
  EXPECT_NEAR(heights[0], 0.06, 0.002);  // box B, box A, the can
  EXPECT_NEAR(heights[1], 0.10, 0.002);
  EXPECT_NEAR(heights[2], 0.12, 0.002);
  // Usage: only with --tabletop-only.
  EXPECT_EQ(run(eval() + " --model " + zero_model_path() + " -q --objects " + out + " " + scene)
                .exit_code,
            2);
}

TEST_F(PipelineCli, WritesTheConfusionMatrixAsPng) {
  const std::string png = dir_->file("confusion.png");
  const Result r = run(eval() + " --model " + zero_model_path() + " -q --confusion-png " + png +
                       " " + scene_path());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const test::Decoded decoded = test::decode_png(png);
  EXPECT_GT(decoded.width, 200);
  EXPECT_GT(decoded.distinct_colors(), 4u);
}

TEST_F(PipelineCli, MissingFileFailsWithOneLine) {
  const Result r = run(eval() + " --model " + zero_model_path() + " -q /nonexistent/scene.pcd");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("primlabel-eval: error:"), std::string::npos) << r.output;
}

TEST_F(PipelineCli, CorruptModelFailsWithOneLine) {
  const std::string corrupt = dir_->file("corrupt.plm");
  std::ofstream(corrupt) << "PRIMLABEL-MODEL\nnot a protobuf at all";
  const Result r = run(eval() + " --model " + corrupt + " -q " + scene_path());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  const std::string missing = dir_->file("missing.plm");
  EXPECT_EQ(run(eval() + " --model " + missing + " -q " + scene_path()).exit_code, 1);
}

TEST_F(PipelineCli, BadUsageExitsTwo) {
  for (const std::string& command :
       {eval() + " --model", eval() + " --bogus-flag x.pcd", eval() + " x.pcd",
        eval() + " --model m.plm --no-truth --confusion-png c.png x.pcd",
        test::binary("primlabel-train") + " --kind nonsense -o m.plm",
        test::binary("primlabel-train") + " --synth-train 1",
        test::binary("primlabel-train") + " --kind svm --curve c.csv -o m.plm",
        // Synthetic validation scenes, or a sensor other than theirs, with files alone.
        test::binary("primlabel-train") + " --train a.pcd --synth-val 1 -o m.plm",
        test::binary("primlabel-train") +
            " --train a.pcd --synth-train 1 --sensor-name kinect -o m.plm",
        test::binary("primlabel-train") + " --node-knots 0 -o m.plm",
        test::binary("primlabel-train") + " --node-knots 0,0.2,0.2 -o m.plm",
        // Bad augmentation specs, and augmentation of files (only synthetic scenes are rescanned).
        test::binary("primlabel-train") + " --augment colour=1 -o m.plm",
        test::binary("primlabel-train") + " --augment noise=4:1 -o m.plm",
        test::binary("primlabel-train") + " --augment density=0:1 -o m.plm",
        test::binary("primlabel-train") + " --train a.pcd --augment noise=1:2 -o m.plm",
        // Multi-scale input: FPFH only, at most 4 further radii, each > 0.
        test::binary("primlabel-train") + " --descriptor pfh --surface-variation -o m.plm",
        test::binary("primlabel-train") + " --extra-radii 0.01,0.02,0.03,0.04,0.05 -o m.plm",
        test::binary("primlabel-train") + " --extra-radii 0.01,-0.02 -o m.plm"}) {
    const Result r = run(command);
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << command << "\n" << r.output;
  }
}

// Each training scene is also described as its augmented variant (seeded: the same draw twice).
TEST_F(PipelineCli, TrainAugmentsTheTrainingScenes) {
  const std::string command = test::binary("primlabel-train") +
                              " --synth-train 1 --synth-val 0 --kind node --iterations 5 "
                              "--threads 2 --augment noise=2,density=0.5 -o " +
                              dir_->file("augmented.plm");
  const Result r = run(command);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("training: synth:lms400:train:seed1000, "), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("training: synth:lms400:train:seed1000:aug0(noise 2.00, keep 0.50, "
                          "range 1.00, elevation +0.0)"),
            std::string::npos)
      << r.output;
  const LabelModel model = load_model(dir_->file("augmented.plm"));
  EXPECT_EQ(model.training.scenes, 2u);
}

// --train files beside --synth-train scenes: one training set (real scans with the simulator's),
// validated on --val files and --synth-val scenes; the model records both and the attribution.
TEST_F(PipelineCli, TrainOnFilesBesideSyntheticScenes) {
  const std::string path = dir_->file("mixed.plm");
  const Result r =
      run(test::binary("primlabel-train") + " --train " + scene_path() + " --val " + scene_path() +
          " --synth-train 1 --synth-val 1 --kind node --iterations 5 --threads 2 "
          "--attribution 'Test data (CC0)' -o " +
          path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("training: " + scene_path() + ", "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("training: synth:lms400:train:seed1000, "), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("validation: " + scene_path() + ", "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("validation: synth:lms400:val:"), std::string::npos) << r.output;
  const LabelModel model = load_model(path);
  EXPECT_EQ(model.training.scenes, 2u);
  ASSERT_EQ(model.training.sources.size(), 2u);
  EXPECT_EQ(model.training.sources[0], scene_path());
  EXPECT_EQ(model.training.sources[1], "synth:lms400:train:seed1000");
  EXPECT_EQ(model.training.sensor, "lms400");  // the synthetic scenes' sensor
  EXPECT_EQ(model.training.data_attribution, "Test data (CC0)");
}

// --voxel-size trains on voxel centroids and records the size, so label_cloud (and the server)
// serves the model at the density it was trained at.
TEST_F(PipelineCli, TrainAtAVoxelSizeRecordsItAndEvalAppliesIt) {
  const std::string path = dir_->file("voxel.plm");
  const Result r = train_on_one_scene(
      "--kind node --iterations 30 --normal-radius 0.02 --feature-radius 0.04 --voxel-size 0.008",
      path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const LabelModel model = load_model(path);
  EXPECT_FLOAT_EQ(model.features.voxel_size, 0.008f);
  // The scene was described as voxels: centroids about half an edge apart or more (partly filled
  // voxels pull them closer), not the scanner's 2 mm.
  EXPECT_GT(model.training.point_spacing_min, 0.0035f);
  EXPECT_LT(model.training.point_spacing_max, 0.010f);
  const Result e = run(eval() + " --model " + path + " --json -q --threads 2 " + scene_path());
  ASSERT_EQ(e.exit_code, 0) << e.output;
  EXPECT_NE(e.output.find("\"accuracy\":0."), std::string::npos) << e.output;
  EXPECT_EQ(e.output.find("domain"), std::string::npos) << e.output;  // served at its density
}

// The research modes are primlabel-research's subcommands now (issue 32): primlabel-eval refuses
// their flags with one line naming the subcommand, and exits 2 before reading anything.
TEST_F(PipelineCli, EvalRefusesTheResearchModesNamingTheirSubcommand) {
  const std::string model = " --model " + zero_model_path() + " ";
  for (const auto& [arguments, subcommand] : std::vector<std::pair<std::string, std::string>>{
           {" --table1 --json", "table1"},
           {" --fig4 out", "fig4"},
           {" --fig4-scenes 2", "fig4"},
           {model + "--mosd-report out --object-truth " + scene_path(), "mosd-report"},
           {model + "--object-truth " + scene_path(), "mosd-report"},
           {" --write-truth t " + scene_path(), "write-truth"},
           {" --truth-check 4", "truth-check"},
           {" --calibrate-kinect dir --fit-simulation", "calibrate-kinect"},
           {" --calibration-json=c.json", "calibrate-kinect"},
           {" --node-knots 0,0.5,1 --table1", "table1"}}) {
    const Result r = run(eval() + arguments);
    EXPECT_EQ(r.exit_code, 2) << arguments << "\n" << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << arguments << "\n" << r.output;
    EXPECT_NE(r.output.find("primlabel-eval: usage error: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("`primlabel-research " + subcommand + "`"), std::string::npos)
        << arguments << "\n"
        << r.output;
  }
  // After "--" a file may have any name.
  const Result file = run(eval() + model + "-q -- --table1");
  EXPECT_EQ(file.exit_code, 1) << file.output;  // no such file, not a usage error
}

TEST_F(PipelineCli, TrainMissingFileFails) {
  const Result r = run(test::binary("primlabel-train") + " --train /nonexistent/a.pcd -q -o " +
                       dir_->file("x.plm"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
}

}  // namespace
}  // namespace primlabel
