// Which model labels a request that names none (pipeline/model_choice.hpp), and the signature
// it reads off a cloud (pipeline/cloud_signature.hpp).

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "primlabel/geometry/cloud_signature.hpp"
#include "primlabel/pipeline/model_choice.hpp"

namespace primlabel::pipeline {
namespace {

// A camera model: trained on 640x480 frames, rough and ~2 mm apart.
TrainingSummary camera() {
  TrainingSummary t;
  t.sensor = "kinect";
  t.image_width = 640, t.image_height = 480;
  t.acquired_spacing_min = 0.0015f, t.acquired_spacing_max = 0.003f;
  t.roughness_min = 0.0015f, t.roughness_max = 0.004f;
  return t;
}

// A laser scanner: unorganised, smooth, ~1 mm apart.
TrainingSummary scanner() {
  TrainingSummary t;
  t.sensor = "lms400";
  t.acquired_spacing_min = 0.0008f, t.acquired_spacing_max = 0.0012f;
  t.roughness_min = 0.0001f, t.roughness_max = 0.0003f;
  return t;
}

TrainingSummary unrecorded() { return {}; }  // a model file from before the domain was recorded

struct Models {
  TrainingSummary cam = camera(), laser = scanner(), old = unrecorded();
  std::vector<ModelCandidate> both() const { return {{"cam", &cam}, {"laser", &laser}}; }
};

TEST(ModelChoice, AFrameGoesToTheModelTrainedOnFramesOfItsSize) {
  const Models m;
  const ModelChooser chooser(m.both(), "laser", CloudShape{640, 480});
  ASSERT_TRUE(chooser.decided());  // no signature needed: the header decides
  EXPECT_EQ(chooser.choice().model, "cam");
  EXPECT_EQ(chooser.choice().reason, ChoiceReason::kDomain);
  EXPECT_NE(chooser.choice().why.find("640x480"), std::string::npos) << chooser.choice().why;
}

TEST(ModelChoice, AFrameOfAnotherSizeIsLeftToTheSignatureAmongCameraModels) {
  const Models m;
  ModelChooser chooser(m.both(), "laser", CloudShape{320, 240});
  ASSERT_TRUE(chooser.needs_signature());
  ASSERT_EQ(chooser.remaining().size(), 1u);  // the scanner model cannot read a frame
  EXPECT_EQ(chooser.remaining().front().name, "cam");
  chooser.consider(CloudSignature{0.004f, 0.003f});  // a coarser camera
  EXPECT_EQ(chooser.choice().model, "cam");
  EXPECT_EQ(chooser.choice().reason, ChoiceReason::kDomain);
}

TEST(ModelChoice, AnUnorganisedCloudIsChosenBySpacingAndRoughness) {
  const Models m;
  ModelChooser laser_scan(m.both(), "cam", CloudShape{});
  ASSERT_TRUE(laser_scan.needs_signature());
  laser_scan.consider(CloudSignature{0.001f, 0.0002f});
  EXPECT_EQ(laser_scan.choice().model, "laser");
  EXPECT_EQ(laser_scan.choice().reason, ChoiceReason::kDomain);

  ModelChooser camera_cloud(m.both(), "laser", CloudShape{});  // a frame sent unorganised
  camera_cloud.consider(CloudSignature{0.002f, 0.0025f});
  EXPECT_EQ(camera_cloud.choice().model, "cam");
  EXPECT_EQ(camera_cloud.choice().reason, ChoiceReason::kDomain);
}

TEST(ModelChoice, SeveralOrNoneFittingFallBackToTheDefault) {
  Models m;
  m.laser.roughness_max = 0.003f;  // a scanner trained with heavy noise: both fit a rough cloud
  ModelChooser several(m.both(), "laser", CloudShape{});
  several.consider(CloudSignature{0.0015f, 0.002f});
  EXPECT_EQ(several.choice().model, "laser");
  EXPECT_EQ(several.choice().reason, ChoiceReason::kDefault);
  EXPECT_NE(several.choice().why.find("several"), std::string::npos) << several.choice().why;

  ModelChooser none(m.both(), "cam", CloudShape{});
  none.consider(CloudSignature{0.05f, 0.02f});  // 5 cm apart: neither sensor
  EXPECT_EQ(none.choice().model, "cam");
  EXPECT_EQ(none.choice().reason, ChoiceReason::kDefault);
  EXPECT_NE(none.choice().why.find("no model fits"), std::string::npos) << none.choice().why;
  // The spacing as acquired, named so: the domain warning speaks of the spacing as described.
  EXPECT_NE(none.choice().why.find("acquired spacing 50.00 mm"), std::string::npos)
      << none.choice().why;
}

TEST(ModelChoice, WithoutADefaultTheRefusalNamesTheCandidates) {
  const Models m;
  ModelChooser chooser(m.both(), "", CloudShape{});
  chooser.consider(CloudSignature{0.05f, 0.02f});
  EXPECT_TRUE(chooser.choice().model.empty());
  EXPECT_NE(chooser.choice().why.find("cam, laser"), std::string::npos) << chooser.choice().why;
  EXPECT_NE(chooser.choice().why.find("no default model"), std::string::npos);
}

TEST(ModelChoice, ADefaultThatIsNotServedIsNoDefault) {
  const Models m;
  ModelChooser chooser(m.both(), "gone", CloudShape{});
  chooser.consider(CloudSignature{0.05f, 0.02f});
  EXPECT_TRUE(chooser.choice().model.empty()) << chooser.choice().model;
}

TEST(ModelChoice, ModelsThatRecordNoDomainAreNeverChosenByIt) {
  const Models m;
  // Only old files: nothing to measure the cloud against, so no index is built.
  const ModelChooser old_only({{"old", &m.old}, {"older", &m.old}}, "older", CloudShape{});
  ASSERT_TRUE(old_only.decided());
  EXPECT_EQ(old_only.choice().model, "older");
  EXPECT_EQ(old_only.choice().reason, ChoiceReason::kDefault);
  // An old file beside a recorded one: the recorded one is chosen only where it fits.
  ModelChooser mixed({{"cam", &m.cam}, {"old", &m.old}}, "old", CloudShape{});
  mixed.consider(CloudSignature{0.002f, 0.0025f});
  EXPECT_EQ(mixed.choice().model, "cam");
  EXPECT_EQ(mixed.choice().reason, ChoiceReason::kDomain);
}

TEST(ModelChoice, TheOnlyModelServedNeedsNoSignature) {
  const Models m;
  const ModelChooser chooser({{"laser", &m.laser}}, "laser", CloudShape{});
  ASSERT_TRUE(chooser.decided());
  EXPECT_EQ(chooser.choice().model, "laser");
  EXPECT_EQ(chooser.choice().reason, ChoiceReason::kDefault);
}

TEST(ModelChoice, AFrameNoModelCanReadFallsBackWithTheReasons) {
  const Models m;
  const ModelChooser chooser({{"laser", &m.laser}, {"laser2", &m.laser}}, "laser2",
                             CloudShape{640, 480});
  ASSERT_TRUE(chooser.decided());
  EXPECT_EQ(chooser.choice().model, "laser2");
  EXPECT_EQ(chooser.choice().reason, ChoiceReason::kDefault);
  EXPECT_NE(chooser.choice().why.find("unorganised lms400 scans"), std::string::npos)
      << chooser.choice().why;
}

TEST(ModelChoice, TheShapeVerdictsAreThreeWay) {
  EXPECT_EQ(judge_shape(camera(), CloudShape{640, 480}).fit, DomainFit::kFits);
  EXPECT_EQ(judge_shape(camera(), CloudShape{320, 240}).fit, DomainFit::kUnknown);
  EXPECT_EQ(judge_shape(camera(), CloudShape{}).fit, DomainFit::kUnknown);
  EXPECT_EQ(judge_shape(scanner(), CloudShape{640, 480}).fit, DomainFit::kOutside);
  EXPECT_EQ(judge_shape(unrecorded(), CloudShape{640, 480}).fit, DomainFit::kUnknown);
  EXPECT_EQ(judge_shape(camera(), CloudShape{640, 1}).fit, DomainFit::kUnknown);  // one row
}

TEST(ModelChoice, TheSignatureToleranceIsTwoEachWay) {
  const TrainingSummary t = scanner();  // spacing 0.8-1.2 mm, roughness 0.1-0.3 mm
  EXPECT_EQ(judge_signature(t, CloudSignature{0.0024f, 0.0006f}).fit, DomainFit::kFits);
  EXPECT_EQ(judge_signature(t, CloudSignature{0.0026f, 0.0002f}).fit, DomainFit::kOutside);
  EXPECT_EQ(judge_signature(t, CloudSignature{0.001f, 0.00004f}).fit, DomainFit::kOutside);
  const float nan = std::nanf("");
  EXPECT_EQ(judge_signature(t, CloudSignature{nan, nan}).fit, DomainFit::kUnknown);
  EXPECT_EQ(judge_signature(unrecorded(), CloudSignature{0.001f, 0.0002f}).fit,
            DomainFit::kUnknown);
}

// A 20 cm square grid of `spacing` with Gaussian depth noise `sigma`.
std::vector<Vec3f> noisy_plane(float spacing, float sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, sigma);
  std::vector<Vec3f> points;
  const int n = int(std::lround(0.2f / spacing));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      points.emplace_back(i * spacing, j * spacing, 1.0f + (sigma > 0 ? noise(rng) : 0.0f));
  return points;
}

TEST(CloudSignature, ReadsTheSpacingAndTheNoiseOfAPlane) {
  const CloudSignature clean = measure_signature(noisy_plane(0.002f, 0.0f, 1), Vec3f::Zero());
  EXPECT_NEAR(clean.point_spacing, 0.002f, 1e-5f);
  EXPECT_LT(clean.roughness, 1e-5f);
  const CloudSignature rough = measure_signature(noisy_plane(0.002f, 0.001f, 2), Vec3f::Zero());
  EXPECT_NEAR(rough.roughness, 0.001f, 0.0002f);  // the RMS to the plane is the noise
  EXPECT_GT(rough.point_spacing, 0.0015f);
  EXPECT_LT(rough.point_spacing, 0.0025f);
}

TEST(CloudSignature, InvalidPixelsAndThreadsDoNotChangeIt) {
  std::vector<Vec3f> points = noisy_plane(0.002f, 0.001f, 3);
  const CloudSignature one = measure_signature(points, Vec3f::Zero(), RunContext{1});
  const CloudSignature two = measure_signature(points, Vec3f::Zero(), RunContext{2});
  EXPECT_EQ(one.point_spacing, two.point_spacing);
  EXPECT_EQ(one.roughness, two.roughness);
  const float nan = std::nanf("");
  std::vector<Vec3f> with_holes;  // every other pixel invalid, as a frame's shadows
  for (const Vec3f& p : points) {
    with_holes.push_back(p);
    with_holes.emplace_back(nan, nan, nan);
  }
  const CloudSignature holed = measure_signature(with_holes, Vec3f::Zero());
  EXPECT_EQ(holed.point_spacing, one.point_spacing);
  EXPECT_EQ(holed.roughness, one.roughness);
  EXPECT_TRUE(std::isnan(one.noise_growth));  // a plane at one range: no growth to read
}

TEST(CloudSignature, AnEmptyOrSinglePointCloudHasNone) {
  const CloudSignature empty = measure_signature({}, Vec3f::Zero());
  EXPECT_TRUE(std::isnan(empty.point_spacing));
  EXPECT_TRUE(std::isnan(empty.roughness));
  const CloudSignature single = measure_signature({Vec3f(1, 2, 3), Vec3f(1, 2, 3)}, Vec3f::Zero());
  EXPECT_TRUE(std::isnan(single.point_spacing));  // coincident copies are no spacing
  EXPECT_TRUE(std::isnan(single.roughness));
}

// A table seen from a sensor at the origin: a plane z = -0.4 from 0.6 m to 1.6 m ahead, 2 mm
// apart, with noise along the viewing ray of sigma(range) = sigma1 * range^growth.
std::vector<Vec3f> receding_table(float sigma1, float growth, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> unit(0.0f, 1.0f);
  std::vector<Vec3f> points;
  for (float y = 0.6f; y <= 1.6f; y += 0.002f)
    for (float x = -0.3f; x <= 0.3f; x += 0.002f) {
      const Vec3f p(x, y, -0.4f);
      const float range = p.norm();
      points.push_back(p + p / range * (sigma1 * std::pow(range, growth) * unit(rng)));
    }
  return points;
}

TEST(CloudSignature, TheNoiseGrowthTellsADepthCameraFromALaserScanner) {
  const CloudSignature camera = measure_signature(receding_table(0.0008f, 2.0f, 4), Vec3f::Zero());
  const CloudSignature scanner = measure_signature(receding_table(0.0008f, 0.0f, 5), Vec3f::Zero());
  EXPECT_NEAR(camera.noise_growth, 2.0f, 0.5f);
  EXPECT_NEAR(scanner.noise_growth, 0.0f, 0.5f);
  // The noise level alone does not change it: a noisier scanner still grows like a scanner.
  const CloudSignature noisy = measure_signature(receding_table(0.003f, 0.0f, 6), Vec3f::Zero());
  EXPECT_NEAR(noisy.noise_growth, 0.0f, 0.5f);
  // All at one range: nothing to say.
  EXPECT_TRUE(std::isnan(
      measure_signature(noisy_plane(0.002f, 0.001f, 7), Vec3f(0.1f, 0.1f, 0)).noise_growth));
}

TEST(ModelChoice, TheNoiseGrowthSeparatesSensorsWhoseSpacingAndNoiseOverlap) {
  TrainingSummary cam = camera(), laser = scanner();
  laser.acquired_spacing_max = cam.acquired_spacing_max;  // a scanner trained at 0.5-4x noise
  laser.roughness_max = 0.005f;
  cam.noise_growth_min = 1.6f, cam.noise_growth_max = 2.2f;
  laser.noise_growth_min = -0.3f, laser.noise_growth_max = 0.2f;
  const std::vector<ModelCandidate> both{{"cam", &cam}, {"laser", &laser}};
  ModelChooser camera_cloud(both, "laser", CloudShape{});
  camera_cloud.consider(CloudSignature{0.002f, 0.002f, 1.9f});
  EXPECT_EQ(camera_cloud.choice().model, "cam");
  EXPECT_EQ(camera_cloud.choice().reason, ChoiceReason::kDomain);
  EXPECT_NE(camera_cloud.choice().why.find("noise growth 1.90"), std::string::npos)
      << camera_cloud.choice().why;
  ModelChooser noisy_scan(both, "cam", CloudShape{});
  noisy_scan.consider(CloudSignature{0.002f, 0.002f, 0.1f});
  EXPECT_EQ(noisy_scan.choice().model, "laser");
  EXPECT_EQ(noisy_scan.choice().reason, ChoiceReason::kDomain);
  // Unmeasurable growth (a cloud at one range): spacing and roughness alone, both fit.
  ModelChooser flat(both, "cam", CloudShape{});
  flat.consider(CloudSignature{0.002f, 0.002f});
  EXPECT_EQ(flat.choice().reason, ChoiceReason::kDefault);
  // The tolerance is 0.5 each way.
  EXPECT_EQ(judge_signature(cam, CloudSignature{0.002f, 0.002f, 1.15f}).fit, DomainFit::kFits);
  EXPECT_EQ(judge_signature(cam, CloudSignature{0.002f, 0.002f, 1.05f}).fit, DomainFit::kOutside);
}

// The receding table as a depth camera in its own frame (z ahead) sees it: depths quantised to
// disparity steps of z^2 / 345 m (a Kinect's 1/8 pixel), or to whole millimetres (OpenNI).
std::vector<Vec3f> quantised_table(bool whole_millimetres) {
  std::vector<Vec3f> points;
  for (const Vec3f& p : receding_table(0.0008f, 2.0f, 8)) {
    const float z = p.y();  // the camera looks along y here: its depth axis becomes z
    const double level =
        whole_millimetres ? std::round(z * 1000.0) / 1000.0 : 345.0 / std::round(345.0 / z);
    points.emplace_back(p.x(), p.z(), float(level));
  }
  return points;
}

TEST(CloudSignature, DepthTiesTellQuantisedDepthAndNeedASlantedSurface) {
  for (bool millimetres : {false, true}) {
    SCOPED_TRACE(millimetres);
    const CloudSignature camera = measure_signature(quantised_table(millimetres), Vec3f::Zero());
    EXPECT_GT(camera.depth_ties, kQuantisedDepthTies);
  }
  // The same table, continuous depths (a laser scanner, a simulator without quantisation).
  std::vector<Vec3f> continuous;
  for (const Vec3f& p : receding_table(0.0008f, 0.0f, 9))
    continuous.emplace_back(p.x(), p.z(), p.y());
  EXPECT_LT(measure_signature(continuous, Vec3f::Zero()).depth_ties, kQuantisedDepthTies / 4);
  // Every coordinate rounded to millimetres for storage (a text file with three decimals): the
  // ties are the file's, not the sensor's: no verdict.
  std::vector<Vec3f> rounded = continuous;
  for (Vec3f& p : rounded)
    for (int axis = 0; axis < 3; ++axis) p[axis] = std::round(p[axis] * 1000.0f) / 1000.0f;
  EXPECT_TRUE(std::isnan(measure_signature(rounded, Vec3f::Zero()).depth_ties));
  // A noise-free plane at one z ties everywhere, but it is not slanted: no verdict.
  EXPECT_TRUE(
      std::isnan(measure_signature(noisy_plane(0.002f, 0.0f, 10), Vec3f::Zero()).depth_ties));
}

TEST(ModelChoice, QuantisedDepthRulesOutAModelTrainedWithoutIt) {
  TrainingSummary cam = camera(), laser = scanner();
  laser.acquired_spacing_max = cam.acquired_spacing_max;  // spacing and noise overlap
  laser.roughness_max = 0.005f;
  cam.depth_ties_min = 0.3f, cam.depth_ties_max = 0.7f;
  laser.depth_ties_min = 0.0f, laser.depth_ties_max = 0.01f;
  const std::vector<ModelCandidate> both{{"cam", &cam}, {"laser", &laser}};
  // A crop of a frame at one range (growth NaN): the ties alone tell it.
  CloudSignature crop{0.002f, 0.002f};
  crop.depth_ties = 0.45f;
  ModelChooser chooser(both, "laser", CloudShape{});
  chooser.consider(crop);
  EXPECT_EQ(chooser.choice().model, "cam");
  EXPECT_EQ(chooser.choice().reason, ChoiceReason::kDomain);
  const DomainVerdict laser_verdict = judge_signature(laser, crop);
  EXPECT_EQ(laser_verdict.fit, DomainFit::kOutside);
  EXPECT_NE(laser_verdict.why.find("depth ties 0.45"), std::string::npos) << laser_verdict.why;
  // No ties (a frame turned into base_link, or not measurable) say nothing against the camera.
  for (const float ties : {0.0f, std::nanf("")}) {
    CloudSignature plain{0.002f, 0.002f};
    plain.depth_ties = ties;
    EXPECT_EQ(judge_signature(cam, plain).fit, DomainFit::kFits);
    EXPECT_EQ(judge_signature(laser, plain).fit, DomainFit::kFits);
  }
}

}  // namespace
}  // namespace primlabel::pipeline
