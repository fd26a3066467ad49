// Training-scene augmentation (synth/augment.hpp) and the scan variations it draws: random
// subsampling, sensor range and incidence, other scan seeds.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "primlabel/synth/augment.hpp"
#include "primlabel/synth/generate.hpp"

namespace primlabel::synth {
namespace {

TEST(Augment, ParsesTheSpecAndRejectsBadOnes) {
  const Augmentation a =
      parse_augmentation("noise=0.5:4,density=0.25:1,range=0.9:1.4,elevation=-10:10,copies=2");
  EXPECT_EQ(a.noise.lo, 0.5);
  EXPECT_EQ(a.noise.hi, 4);
  EXPECT_EQ(a.density.lo, 0.25);
  EXPECT_EQ(a.range.hi, 1.4);
  EXPECT_EQ(a.elevation_deg.lo, -10);
  EXPECT_EQ(a.copies, 2);
  EXPECT_EQ(to_string(a), "noise=0.5:4,density=0.25:1,range=0.9:1.4,elevation=-10:10,copies=2");
  const Augmentation only_noise = parse_augmentation("noise=2");
  EXPECT_EQ(only_noise.copies, 1);
  EXPECT_EQ(only_noise.noise.lo, 2);
  EXPECT_EQ(only_noise.density.lo, 1);
  for (const char* bad : {"noise", "noise=4:0.5", "density=0:1", "density=0.5:1.5", "colour=1",
                          "copies=0", "copies=1.5", "range=x", "elevation=-80:0"})
    EXPECT_THROW(parse_augmentation(bad), std::invalid_argument) << bad;
}

TEST(Augment, DrawsAreSeededAndWithinTheRanges) {
  const Augmentation a =
      parse_augmentation("noise=0.5:4,density=0.25:1,range=0.9:1.4,elevation=-10:10");
  GenerateOptions base;
  base.seed = 1003;
  const GenerateOptions first = augmented(base, a, 0), again = augmented(base, a, 0);
  EXPECT_EQ(first.noise_scale, again.noise_scale);
  EXPECT_EQ(first.keep, again.keep);
  EXPECT_EQ(first.scan_seed, again.scan_seed);
  EXPECT_EQ(first.seed, base.seed);  // the same scene, scanned otherwise
  EXPECT_NE(augmented(base, a, 1).noise_scale, first.noise_scale);
  std::vector<double> noise;
  for (int seed = 1000; seed < 1400; ++seed) {
    base.seed = seed;
    const GenerateOptions v = augmented(base, a, 0);
    ASSERT_TRUE(v.scan_seed.has_value());
    EXPECT_NE(*v.scan_seed, base.seed);
    EXPECT_GE(v.noise_scale, 0.5);
    EXPECT_LE(v.noise_scale, 4.0);
    EXPECT_GE(v.keep, 0.25);
    EXPECT_LE(v.keep, 1.0);
    EXPECT_GE(v.placement.range_scale, 0.9);
    EXPECT_LE(v.placement.range_scale, 1.4);
    EXPECT_GE(v.placement.elevation_deg, -10.0);
    EXPECT_LE(v.placement.elevation_deg, 10.0);
    noise.push_back(v.noise_scale);
  }
  // Log-uniform: the median near the geometric mean sqrt(0.5 * 4) = 1.41, not (0.5 + 4) / 2.
  std::nth_element(noise.begin(), noise.begin() + noise.size() / 2, noise.end());
  EXPECT_NEAR(noise[noise.size() / 2], std::sqrt(2.0), 0.2);
}

TEST(Augment, NominalOptionsScanAsBefore) {
  GenerateOptions options;
  options.seed = 1001;
  const Generated nominal = generate(options);
  const PointCloud reference = synthetic_scene(SceneSet::kTrain, 1, SensorKind::kLms400);
  ASSERT_EQ(nominal.cloud.size(), reference.size());
  for (std::size_t i = 0; i < reference.size(); i += 97)
    EXPECT_EQ(nominal.cloud.xyz[i], reference.xyz[i]) << i;
  EXPECT_EQ(nominal.tags.count("scan"), 0u);  // nominal scans keep their headers
}

TEST(Augment, SubsamplingKeepsTheShareAndTheLayout) {
  GenerateOptions options;
  options.seed = 1002;
  const std::size_t full = generate(options).cloud.size();
  options.keep = 0.35;
  const Generated sparse = generate(options);
  EXPECT_NEAR(double(sparse.cloud.size()) / double(full), 0.35, 0.01);
  EXPECT_EQ(sparse.cloud.height, 1u);
  EXPECT_EQ(sparse.cloud.labels.size(), sparse.cloud.size());
  EXPECT_EQ(sparse.cloud.find_field("object")->values.size(), sparse.cloud.size());
  EXPECT_NE(sparse.tags.at("scan").find("keep=0.35"), std::string::npos);

  options.sensor = SensorKind::kKinect;
  options.keep = 1.0;
  const PointCloud frame = generate(options).cloud;
  options.keep = 0.5;
  const PointCloud half = generate(options).cloud;
  ASSERT_EQ(half.size(), frame.size());  // organised: same pixels, dropped ones NaN
  EXPECT_EQ(half.width, 640u);
  std::size_t returned = 0, kept = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    returned += is_finite(frame.xyz[i]);
    kept += is_finite(half.xyz[i]);
    if (!is_finite(half.xyz[i])) EXPECT_EQ(half.labels[i], 0u);
  }
  EXPECT_NEAR(double(kept) / double(returned), 0.5, 0.01);
}

double mean_range(const PointCloud& cloud) {
  double sum = 0;
  std::size_t n = 0;
  for (const Vec3f& p : cloud.xyz)
    if (is_finite(p)) sum += (p - cloud.viewpoint.origin).norm(), ++n;
  return sum / double(n);
}

TEST(Augment, PlacementChangesRangeAndIncidence) {
  for (SensorKind sensor : {SensorKind::kLms400, SensorKind::kKinect}) {
    GenerateOptions options;
    options.seed = 1004;
    options.sensor = sensor;
    const PointCloud nominal = generate(options).cloud;
    options.placement.range_scale = 1.3;
    const PointCloud far = generate(options).cloud;
    EXPECT_GT(mean_range(far), 1.15 * mean_range(nominal));
    options.placement.range_scale = 1.0;
    options.placement.elevation_deg = 10;
    const PointCloud steep = generate(options).cloud;
    // Turned up about the table's front edge: the sensor is higher, at a similar distance.
    EXPECT_GT(steep.viewpoint.origin.z(), nominal.viewpoint.origin.z() + 0.05f);
    EXPECT_NEAR(mean_range(steep), mean_range(nominal), 0.15 * mean_range(nominal));
  }
  GenerateOptions bad;
  bad.keep = 0;
  EXPECT_THROW(generate(bad), std::invalid_argument);
}

}  // namespace
}  // namespace primlabel::synth
