#include "primlabel/synth/generate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "primlabel/synth/random.hpp"

namespace primlabel::synth {

Generated generate(const GenerateOptions& options) {
  if (!(options.label_radius > 0)) throw std::invalid_argument("the label radius must be positive");
  if (!(options.noise_scale >= 0)) throw std::invalid_argument("the noise scale must be >= 0");
  if (options.dropout && !(*options.dropout >= 0 && *options.dropout < 1))
    throw std::invalid_argument("the dropout probability must be in [0, 1)");

  if (!(options.keep > 0 && options.keep <= 1))
    throw std::invalid_argument("the share of points kept must be in (0, 1]");
  if (!(options.placement.range_scale > 0))
    throw std::invalid_argument("the sensor range scale must be positive");
  if (!(std::abs(options.placement.elevation_deg) < 60))
    throw std::invalid_argument("the sensor elevation change must be within +-60 degrees");

  Generated out;
  out.scene = make_scene(options.scene, options.seed, options.table);
  const std::uint64_t scan_seed = options.scan_seed.value_or(options.seed);
  if (options.sensor == SensorKind::kLms400) {
    Lms400Options lms = lms400_for_scene(out.scene, scan_seed, options.placement);
    lms.range_noise *= options.noise_scale;
    if (options.dropout) lms.dropout = *options.dropout;
    if (options.lms400_lines) lms.lines = *options.lms400_lines;
    if (options.lms400_angular_step_deg) lms.angular_step_deg = *options.lms400_angular_step_deg;
    out.cloud = scan_lms400(out.scene, lms, options.label_radius, scan_seed);
  } else {
    KinectOptions kinect = kinect_for_scene(out.scene, scan_seed, options.placement);
    kinect.depth_noise *= options.noise_scale;
    if (options.noise_scale == 0) kinect.quantize = false;
    if (options.dropout) kinect.dropout = *options.dropout;
    out.cloud = scan_kinect(out.scene, kinect, options.label_radius, scan_seed);
  }
  if (options.keep < 1) subsample(out.cloud, options.keep, scan_seed);

  char radius[32];
  std::snprintf(radius, sizeof radius, "%.6g", options.label_radius);
  out.tags["generator"] = "primlabel-synth 1";
  out.tags["scene"] = std::string(scene_name(options.scene));
  out.tags["sensor"] = std::string(sensor_name(options.sensor));
  out.tags["seed"] = std::to_string(options.seed);
  out.tags["label_radius"] = radius;
  out.tags["objects"] = describe_objects(out.scene);
  out.tags["classes"] = class_map_tag(ClassMap::taxonomy());
  // How the scan departs from the sensor's nominal model (only when it does: default scans keep
  // their headers).
  char value[128];
  if (options.noise_scale != 1.0 || options.keep != 1.0 || options.scan_seed ||
      options.placement.range_scale != 1.0 || options.placement.elevation_deg != 0.0) {
    std::snprintf(value, sizeof value,
                  "noise=%.6g keep=%.6g range=%.6g elevation=%.6g scan_seed=%llu",
                  options.noise_scale, options.keep, options.placement.range_scale,
                  options.placement.elevation_deg, static_cast<unsigned long long>(scan_seed));
    out.tags["scan"] = value;
  }
  return out;
}

void subsample(PointCloud& cloud, double keep, std::uint64_t seed) {
  constexpr std::uint64_t kKeepStream = 301;
  auto kept = [&](std::size_t i) { return Rng(mix_seed(seed, kKeepStream, i)).uniform() < keep; };
  if (cloud.organized()) {
    FloatField* object = cloud.find_field("object");
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (kept(i)) continue;
      cloud.xyz[i] = Vec3f::Constant(NAN);
      if (cloud.has_labels()) cloud.labels[i] = 0;
      if (cloud.has_rgba()) cloud.rgba[i] = 0;
      if (object) object->values[i] = -1;
    }
    return;
  }
  std::size_t n = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!kept(i)) continue;
    cloud.xyz[n] = cloud.xyz[i];
    if (cloud.has_labels()) cloud.labels[n] = cloud.labels[i];
    if (cloud.has_rgba()) cloud.rgba[n] = cloud.rgba[i];
    if (cloud.has_normals()) cloud.normals[n] = cloud.normals[i];
    if (cloud.has_curvature()) cloud.curvature[n] = cloud.curvature[i];
    for (FloatField& f : cloud.fields) std::copy_n(f.row(i), f.count, f.row(n));
    ++n;
  }
  cloud.xyz.resize(n);
  if (cloud.has_labels()) cloud.labels.resize(n);
  if (cloud.has_rgba()) cloud.rgba.resize(n);
  if (cloud.has_normals()) cloud.normals.resize(n);
  if (cloud.has_curvature()) cloud.curvature.resize(n);
  for (FloatField& f : cloud.fields) f.values.resize(n * std::size_t(f.count));
  cloud.width = static_cast<std::uint32_t>(n);
  cloud.height = 1;
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
    case SceneKind::kClutter:
      return "clutter";
    case SceneKind::kCrowded:
      return "crowded";
  }
  return "table";
}

std::optional<SceneKind> scene_from_name(std::string_view name) {
  for (SceneKind kind : {SceneKind::kTable, SceneKind::kPrimitives, SceneKind::kEmptyTable,
                         SceneKind::kClutter, SceneKind::kCrowded})
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
