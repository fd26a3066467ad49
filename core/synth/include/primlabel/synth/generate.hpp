#pragma once
// One call from a seed to a labeled synthetic scan, and the seed ranges of the scene sets.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/synth/scanners.hpp"
#include "primlabel/synth/scene.hpp"

namespace primlabel::synth {

enum class SensorKind { kLms400, kKinect };

// Support radius the labels are defined at, when none is given: the FPFH radius for table-top
// objects scanned at 2-3 mm spacing.
inline constexpr double kDefaultLabelRadius = 0.025;

struct GenerateOptions {
  SceneKind scene = SceneKind::kTable;
  SensorKind sensor = SensorKind::kLms400;
  std::uint64_t seed = 1;
  double label_radius = kDefaultLabelRadius;
  double noise_scale = 1.0;         // multiplies the sensor's nominal noise (0 = exact ranges)
  std::optional<double> dropout;    // overrides the sensor's dropout probability
  std::optional<int> lms400_lines;  // sweep lines (density across lines)
  std::optional<double> lms400_angular_step_deg;  // density along a line
  // Random subsampling: the share of returns kept, each point drawn on its own (seeded); dropped
  // points leave an unorganised cloud and are NaN (label 0, object -1) in an organised one.
  double keep = 1.0;
  SensorPlacement placement;               // range and incidence beyond the seed's jitter
  std::optional<std::uint64_t> scan_seed;  // sensor jitter, noise and subsampling (default: seed)
  TableSceneOptions table;
};

struct Generated {
  Scene scene;
  PointCloud cloud;  // see scanners.hpp for the fields
  CloudTags tags;    // scene, sensor, seed, label_radius, objects, classes, generator
};

Generated generate(const GenerateOptions& options);

// Keeps each point with probability `keep` (its own draw from seed and index): unorganised clouds
// are compacted, organised ones keep their layout with dropped points NaN, label 0, object -1.
void subsample(PointCloud& cloud, double keep, std::uint64_t seed);

std::string_view sensor_name(SensorKind sensor);
std::optional<SensorKind> sensor_from_name(std::string_view name);
std::string_view scene_name(SceneKind scene);
std::optional<SceneKind> scene_from_name(std::string_view name);

// Scene sets draw their seeds from disjoint ranges: train 1000.., val 2000.., test 3000..
enum class SceneSet { kTrain, kVal, kTest };
inline constexpr int kMaxSetSize = 1000;
std::uint64_t set_seed(SceneSet set, int index);  // index < kMaxSetSize
std::string_view set_name(SceneSet set);

// The labeled cloud of scene `index` of a scene set (seed from set_seed, so the sets are disjoint).
PointCloud synthetic_scene(SceneSet set, int index, SensorKind sensor,
                           double label_radius = kDefaultLabelRadius);
std::optional<SceneSet> set_from_name(std::string_view name);

}  // namespace primlabel::synth
