#include "primlabel/synth/generate.hpp"

#include <cstdio>
#include <stdexcept>

namespace primlabel::synth {

Generated generate(const GenerateOptions& options) {
  if (!(options.label_radius > 0)) throw std::invalid_argument("the label radius must be positive");
  if (!(options.noise_scale >= 0)) throw std::invalid_argument("the noise scale must be >= 0");
  if (options.dropout && !(*options.dropout >= 0 && *options.dropout < 1))
    throw std::invalid_argument("the dropout probability must be in [0, 1)");

  Generated out;
  out.scene = make_scene(options.scene, options.seed, options.table);
  if (options.sensor == SensorKind::kLms400) {
    Lms400Options lms = lms400_for_scene(out.scene, options.seed);
    lms.range_noise *= options.noise_scale;
    if (options.dropout) lms.dropout = *options.dropout;
    if (options.lms400_lines) lms.lines = *options.lms400_lines;
    if (options.lms400_angular_step_deg) lms.angular_step_deg = *options.lms400_angular_step_deg;
    out.cloud = scan_lms400(out.scene, lms, options.label_radius, options.seed);
  } else {
    KinectOptions kinect = kinect_for_scene(out.scene, options.seed);
    kinect.depth_noise *= options.noise_scale;
    if (options.noise_scale == 0) kinect.quantize = false;
    if (options.dropout) kinect.dropout = *options.dropout;
    out.cloud = scan_kinect(out.scene, kinect, options.label_radius, options.seed);
  }

  char radius[32];
  std::snprintf(radius, sizeof radius, "%.6g", options.label_radius);
  out.tags["generator"] = "primlabel-synth 1";
  out.tags["scene"] = std::string(scene_name(options.scene));
  out.tags["sensor"] = std::string(sensor_name(options.sensor));
  out.tags["seed"] = std::to_string(options.seed);
  out.tags["label_radius"] = radius;
  out.tags["objects"] = describe_objects(out.scene);
  out.tags["classes"] = class_map_tag(ClassMap::taxonomy());
  return out;
}

std::string_view sensor_name(SensorKind sensor) {
  return sensor == SensorKind::kLms400 ? "lms400" : "kinect";
}

std::optional<SensorKind> sensor_from_name(std::string_view name) {
  if (name == "lms400") return SensorKind::kLms400;
  if (name == "kinect") return SensorKind::kKinect;
  return std::nullopt;
}

std::string_view scene_name(SceneKind scene) {
  switch (scene) {
    case SceneKind::kTable:
      return "table";
    case SceneKind::kPrimitives:
      return "primitives";
    case SceneKind::kEmptyTable:
      return "empty";
  }
  return "table";
}

std::optional<SceneKind> scene_from_name(std::string_view name) {
  for (SceneKind kind : {SceneKind::kTable, SceneKind::kPrimitives, SceneKind::kEmptyTable})
    if (name == scene_name(kind)) return kind;
  return std::nullopt;
}

std::uint64_t set_seed(SceneSet set, int index) {
  if (index < 0 || index >= kMaxSetSize) throw std::invalid_argument("scene index out of range");
  const std::uint64_t base = set == SceneSet::kTrain ? 1000 : set == SceneSet::kVal ? 2000 : 3000;
  return base + static_cast<std::uint64_t>(index);
}

std::string_view set_name(SceneSet set) {
  return set == SceneSet::kTrain ? "train" : set == SceneSet::kVal ? "val" : "test";
}

std::optional<SceneSet> set_from_name(std::string_view name) {
  for (SceneSet set : {SceneSet::kTrain, SceneSet::kVal, SceneSet::kTest})
    if (name == set_name(set)) return set;
  return std::nullopt;
}

PointCloud synthetic_scene(SceneSet set, int index, SensorKind sensor, double label_radius) {
  GenerateOptions options;
  options.sensor = sensor;
  options.seed = set_seed(set, index);
  options.label_radius = label_radius;
  return generate(options).cloud;
}

}  // namespace primlabel::synth
