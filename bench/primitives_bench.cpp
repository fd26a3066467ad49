// primlabel-bench primitives: fitted primitive instances on held-out synthetic LMS400 scenes
// against the shapes the generator placed. Each scene is labeled by a model, and its primitives
// are fitted twice: from the predicted labels (what the service returns) and from the true
// labels (the fit alone). A true surface is an object's curved part (can or mug side, the inside
// of a mug, a ball, a bowl's outside or inside, a ring) with 50 or more truly labeled points; it
// is found when a primitive of its model and class has most of its points on that object. Prints
// a row per scene, the radius and axis errors of the found surfaces and the time to fit.
//
// Then instances (primitive_matching.hpp): every true primitive with 50 or more scan points
// (planes too) against the detections of each detector, scored by the same rule: primlabel from
// the predicted labels, primlabel from the true labels and, when built with CGAL, CGAL's
// Efficient RANSAC (cgal_ransac_peer.hpp) on the same points with the normals primlabel computed.
// Recall, precision, radius and axis errors and wall time of each, and the speed ratio. Last
// line: JSON.
//
//   primlabel-bench primitives --model build/models/tabletop-lms400/1/model.plm --scenes 4

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>

#include "bench_commands.hpp"
#include "primitive_matching.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/primitives/fit_primitives.hpp"
#include "primlabel/synth/generate.hpp"
#include "primlabel/synth/true_primitives.hpp"
#ifdef PRIMLABEL_HAVE_CGAL
#include "cgal_ransac_peer.hpp"
#endif

namespace {

using namespace primlabel;
using primitives::PrimitiveKind;
using Vec3d = Eigen::Vector3d;

struct Arguments {
  std::string model;
  int scenes = 4, threads = 2;
  std::uint64_t first_seed = 3000;  // the test set's seeds (synth::SceneSet::kTest)
  // CGAL's search endurance and connectivity, to check the comparison does not hinge on them.
  double cgal_probability = 0.01;
  double cgal_cluster_spacings = 4;  // cluster epsilon in median point spacings
  bool explain_misses = false;       // print why each true primitive was not matched
};

// A curved surface the generator placed: its model, class and true parameters (world frame).
struct TrueSurface {
  int object = 0;
  PrimitiveKind kind = PrimitiveKind::kCylinder;
  std::uint32_t class_id = 0;
  double radius = 0;  // cylinder, sphere; the torus' major radius
  Vec3d axis = Vec3d::UnitZ();
  std::optional<Vec3d> center;  // spheres
};

// The scene's curved true primitives (synth::true_primitives; its planes are not scored here).
std::vector<TrueSurface> true_surfaces(const synth::Scene& scene) {
  std::vector<TrueSurface> out;
  for (const synth::TruePrimitive& t : synth::true_primitives(scene)) {
    const primitives::Primitive& p = t.primitive;
    if (const auto* c = std::get_if<primitives::CylinderModel>(&p.model))
      out.push_back({t.object, PrimitiveKind::kCylinder, p.class_id, c->radius, c->axis});
    else if (const auto* sp = std::get_if<primitives::SphereModel>(&p.model))
      out.push_back(
          {t.object, PrimitiveKind::kSphere, p.class_id, sp->radius, Vec3d::UnitZ(), sp->center});
    else if (const auto* tr = std::get_if<primitives::TorusModel>(&p.model))
      out.push_back({t.object, PrimitiveKind::kTorus, p.class_id, tr->major_radius, tr->axis});
  }
  return out;
}

struct Match {
  bool found = false;
  double radius_error = NAN;  // |fitted - true| (m)
  double axis_error_deg = NAN;
  double center_error = NAN;  // spheres (m)
};

struct Figures {
  std::size_t surfaces = 0, found = 0;
  std::map<PrimitiveKind, std::size_t> fitted;  // primitives per kind with confidence >= 0.3
  std::vector<double> cylinder_radius, sphere_radius, torus_radius, axis_deg, sphere_center;
  double seconds = 0;
};

using bench::axis_angle_deg;

// The object most points of each primitive's segment lie on.
std::vector<int> majority_objects(const primitives::PrimitiveSet& set, const FloatField& object) {
  std::vector<std::map<int, std::size_t>> votes(set.primitives.size());
  for (std::size_t i = 0; i < set.point_segment.size(); ++i)
    if (set.point_segment[i] != primitives::kNoSegment)
      ++votes[set.point_segment[i]][int(object.values[i])];
  std::vector<int> out;
  for (const auto& v : votes) {
    int best = -1;
    std::size_t most = 0;
    for (const auto& [o, n] : v)
      if (n > most) most = n, best = o;
    out.push_back(best);
  }
  return out;
}

void score(const primitives::PrimitiveSet& set, const std::vector<TrueSurface>& truth,
           const std::vector<std::size_t>& true_points, const FloatField& object, Figures& f) {
  const std::vector<int> owner = majority_objects(set, object);
  for (const auto& p : set.primitives)
    if (p.confidence >= 0.3) ++f.fitted[p.kind()];
  for (std::size_t t = 0; t < truth.size(); ++t) {
    if (true_points[t] < 50) continue;
    const TrueSurface& s = truth[t];
    ++f.surfaces;
    // The largest primitive of this surface's model and class on its object (they come by size).
    for (std::size_t k = 0; k < set.primitives.size(); ++k) {
      const auto& p = set.primitives[k];
      if (owner[k] != s.object || p.kind() != s.kind || p.class_id != s.class_id) continue;
      ++f.found;
      if (const auto* c = std::get_if<primitives::CylinderModel>(&p.model)) {
        f.cylinder_radius.push_back(std::abs(c->radius - s.radius));
        f.axis_deg.push_back(axis_angle_deg(c->axis, s.axis));
      } else if (const auto* sp = std::get_if<primitives::SphereModel>(&p.model)) {
        f.sphere_radius.push_back(std::abs(sp->radius - s.radius));
        if (s.center) f.sphere_center.push_back((sp->center - *s.center).norm());
      } else if (const auto* tr = std::get_if<primitives::TorusModel>(&p.model)) {
        f.torus_radius.push_back(std::abs(tr->major_radius - s.radius));
        f.axis_deg.push_back(axis_angle_deg(tr->axis, s.axis));
      }
      break;
    }
  }
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}
double percentile90(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, std::size_t(0.9 * double(v.size())))];
}

json::Json figures_json(const Figures& f, int scenes) {
  json::Json fitted = json::Json::object();
  for (const auto& [kind, n] : f.fitted) fitted[std::string(primitives::kind_name(kind))] = n;
  auto mm = [](double m) { return json::rounded(1000 * m, "%.3f"); };
  return {
      {"true_surfaces", f.surfaces},
      {"found", f.found},
      {"recall", json::rounded(f.surfaces ? double(f.found) / double(f.surfaces) : NAN, "%.4f")},
      {"fitted_confident", std::move(fitted)},
      {"cylinder_radius_error_mm_median", mm(median(f.cylinder_radius))},
      {"cylinder_radius_error_mm_p90", mm(percentile90(f.cylinder_radius))},
      {"sphere_radius_error_mm_median", mm(median(f.sphere_radius))},
      {"sphere_radius_error_mm_p90", mm(percentile90(f.sphere_radius))},
      {"sphere_center_error_mm_median", mm(median(f.sphere_center))},
      {"torus_major_radius_error_mm_median", mm(median(f.torus_radius))},
      {"axis_error_deg_median", json::rounded(median(f.axis_deg), "%.3f")},
      {"fit_ms_per_scan", json::rounded(1000 * f.seconds / std::max(scenes, 1), "%.1f")}};
}

void print(const char* what, const Figures& f, int scenes) {
  std::printf(
      "%-16s surfaces found %zu/%zu; radius error median/p90 (mm): cylinders %.2f/%.2f (%zu), "
      "spheres %.2f/%.2f (%zu), tori %.2f (%zu); sphere centres %.2f mm; axes %.2f deg; "
      "fit %.0f ms/scan\n",
      what, f.found, f.surfaces, 1000 * median(f.cylinder_radius),
      1000 * percentile90(f.cylinder_radius), f.cylinder_radius.size(),
      1000 * median(f.sphere_radius), 1000 * percentile90(f.sphere_radius), f.sphere_radius.size(),
      1000 * median(f.torus_radius), f.torus_radius.size(), 1000 * median(f.sphere_center),
      median(f.axis_deg), 1000 * f.seconds / scenes);
  std::printf("%-16s confident primitives (>= 0.3):", "");
  for (const auto& [kind, n] : f.fitted)
    std::printf(" %s %zu", std::string(primitives::kind_name(kind)).c_str(), n);
  std::printf("\n");
}

// One detector's instance figures over the scenes (primitive_matching.hpp's rule).
struct InstanceFigures {
  std::size_t true_instances = 0, found = 0, detections = 0, correct = 0;
  std::size_t listed_instances = 0, listed_found = 0;  // by primitive.points (edge bands too)
  std::map<PrimitiveKind, std::pair<std::size_t, std::size_t>> by_kind;  // found, true
  std::vector<double> cylinder_radius, sphere_radius, torus_radius, axis_deg, plane_normal_deg;
  double seconds = 0;  // the detector's own time (fit or detection)
};

void add_match(const bench::InstanceMatch& m, const std::vector<synth::TruePrimitive>& truth,
               const bench::MatchOptions& options, InstanceFigures& f) {
  f.true_instances += m.true_instances;
  f.found += m.found;
  f.listed_instances += m.listed_instances;
  f.listed_found += m.listed_found;
  f.detections += m.detections;
  f.correct += m.correct;
  for (const auto& t : truth)
    if (bench::visible(t, options)) ++f.by_kind[t.primitive.kind()].second;
  for (const bench::MatchedPair& pair : m.pairs) {
    const primitives::Primitive& t = truth[pair.truth].primitive;
    if (!bench::visible(truth[pair.truth], options)) continue;
    ++f.by_kind[t.kind()].first;
    switch (t.kind()) {
      case PrimitiveKind::kCylinder:
        f.cylinder_radius.push_back(pair.radius_error);
        f.axis_deg.push_back(pair.axis_error_deg);
        break;
      case PrimitiveKind::kSphere:
        f.sphere_radius.push_back(pair.radius_error);
        break;
      case PrimitiveKind::kTorus:
        f.torus_radius.push_back(pair.radius_error);
        f.axis_deg.push_back(pair.axis_error_deg);
        break;
      case PrimitiveKind::kPlane:
        f.plane_normal_deg.push_back(pair.axis_error_deg);
        break;
      default:
        break;
    }
  }
}

double ratio(std::size_t a, std::size_t b) { return b ? double(a) / double(b) : NAN; }

json::Json instance_json(const InstanceFigures& f, int scenes) {
  json::Json kinds = json::Json::object();
  for (const auto& [kind, n] : f.by_kind)
    kinds[std::string(primitives::kind_name(kind))] = {{"found", n.first}, {"true", n.second}};
  auto mm = [](double m) { return json::rounded(1000 * m, "%.3f"); };
  std::vector<double> radius = f.cylinder_radius;
  radius.insert(radius.end(), f.sphere_radius.begin(), f.sphere_radius.end());
  return {{"true_instances", f.true_instances},
          {"found", f.found},
          {"recall", json::rounded(ratio(f.found, f.true_instances), "%.4f")},
          {"listed_instances", f.listed_instances},
          {"listed_found", f.listed_found},
          {"listed_recall", json::rounded(ratio(f.listed_found, f.listed_instances), "%.4f")},
          {"detections", f.detections},
          {"correct", f.correct},
          {"precision", json::rounded(ratio(f.correct, f.detections), "%.4f")},
          {"by_kind", std::move(kinds)},
          {"cylinder_sphere_radius_error_mm_median", mm(median(radius))},
          {"cylinder_sphere_radius_error_mm_p90", mm(percentile90(radius))},
          {"cylinder_radius_error_mm_median", mm(median(f.cylinder_radius))},
          {"cylinder_radius_error_mm_p90", mm(percentile90(f.cylinder_radius))},
          {"sphere_radius_error_mm_median", mm(median(f.sphere_radius))},
          {"sphere_radius_error_mm_p90", mm(percentile90(f.sphere_radius))},
          {"torus_major_radius_error_mm_median", mm(median(f.torus_radius))},
          {"axis_error_deg_median", json::rounded(median(f.axis_deg), "%.3f")},
          {"plane_normal_error_deg_median", json::rounded(median(f.plane_normal_deg), "%.3f")},
          {"ms_per_scan", json::rounded(1000 * f.seconds / std::max(scenes, 1), "%.1f")}};
}

void print_instances(const char* what, const InstanceFigures& f, int scenes) {
  std::vector<double> radius = f.cylinder_radius;
  radius.insert(radius.end(), f.sphere_radius.begin(), f.sphere_radius.end());
  std::printf(
      "%-22s recall %zu/%zu = %.3f, precision %zu/%zu = %.3f; radius error median/p90 (mm): "
      "cylinders %.2f/%.2f (%zu), spheres %.2f/%.2f (%zu), both %.2f/%.2f; axes %.2f deg; "
      "plane normals %.2f deg; %.0f ms/scan\n",
      what, f.found, f.true_instances, ratio(f.found, f.true_instances), f.correct, f.detections,
      ratio(f.correct, f.detections), 1000 * median(f.cylinder_radius),
      1000 * percentile90(f.cylinder_radius), f.cylinder_radius.size(),
      1000 * median(f.sphere_radius), 1000 * percentile90(f.sphere_radius), f.sphere_radius.size(),
      1000 * median(radius), 1000 * percentile90(radius), median(f.axis_deg),
      median(f.plane_normal_deg), 1000 * f.seconds / scenes);
  std::printf("%-22s by the listed count (edge-band points too): recall %zu/%zu = %.3f\n", "",
              f.listed_found, f.listed_instances, ratio(f.listed_found, f.listed_instances));
  std::printf("%-22s found/true by kind:", "");
  for (const auto& [kind, n] : f.by_kind)
    std::printf(" %s %zu/%zu", std::string(primitives::kind_name(kind)).c_str(), n.first, n.second);
  std::printf("\n");
}

// For each true primitive with enough points that no detection matched: the detections with
// points on it, how many, how large they are and what they fit (to see why it was missed).
void explain_misses(const char* what, std::uint64_t seed, const primitives::PrimitiveSet& set,
                    const std::vector<Vec3f>& xyz, const FloatField& object,
                    const std::vector<synth::TruePrimitive>& truth, const bench::InstanceMatch& m,
                    const bench::MatchOptions& options) {
  std::vector<bool> matched(truth.size(), false);
  for (const auto& pair : m.pairs) matched[pair.truth] = true;
  for (std::size_t t = 0; t < truth.size(); ++t) {
    const primitives::Primitive& tp = truth[t].primitive;
    if (matched[t] || tp.points < options.min_true_points) continue;
    std::printf("miss %s seed %llu: true %s of object %d, %zu points (%zu its own%s)", what,
                static_cast<unsigned long long>(seed),
                std::string(primitives::kind_name(tp.kind())).c_str(), truth[t].object, tp.points,
                truth[t].own_points, bench::visible(truth[t], options) ? "" : ": not visible");
    if (const auto* pl = std::get_if<primitives::PlaneModel>(&tp.model))
      std::printf(", %.0fx%.0f mm, normal (%.2f %.2f %.2f)", 1000 * pl->extent_u,
                  1000 * pl->extent_v, pl->normal.x(), pl->normal.y(), pl->normal.z());
    std::printf("\n");
    std::map<std::uint32_t, std::size_t> on;
    for (std::size_t i = 0; i < xyz.size(); ++i) {
      const std::uint32_t d = set.point_segment[i];
      if (d == primitives::kNoSegment || int(object.values[i]) != truth[t].object) continue;
      if (synth::distance_to(tp.model, xyz[i].cast<double>()) <= options.tolerance) ++on[d];
    }
    for (const auto& [d, n] : on) {
      const primitives::Primitive& p = set.primitives[d];
      std::printf("    detection %u: %s class %u, %zu points (%zu inliers), %zu on it", d,
                  std::string(primitives::kind_name(p.kind())).c_str(), p.class_id, p.points,
                  p.inliers, n);
      if (const auto* pl = std::get_if<primitives::PlaneModel>(&p.model))
        std::printf(
            ", normal off %.1f deg, %.0fx%.0f mm",
            bench::axis_angle_deg(pl->normal, std::get<primitives::PlaneModel>(tp.model).normal),
            1000 * pl->extent_u, 1000 * pl->extent_v);
      std::printf("\n");
    }
  }
  // The detections no true primitive took (what precision counts against).
  std::vector<bool> taken(set.primitives.size(), false);
  for (const auto& pair : m.pairs) taken[pair.detection] = true;
  for (std::size_t d = 0; d < set.primitives.size(); ++d) {
    const primitives::Primitive& p = set.primitives[d];
    const PrimitiveKind kind = p.kind();
    if (taken[d] || p.points < options.min_detection_points ||
        !(kind == PrimitiveKind::kPlane || kind == PrimitiveKind::kCylinder ||
          kind == PrimitiveKind::kSphere || kind == PrimitiveKind::kTorus))
      continue;
    std::printf(
        "extra %s seed %llu: detection %zu: %s class %u, %zu points (%zu inliers), rms "
        "%.2f mm, confidence %.2f",
        what, static_cast<unsigned long long>(seed), d,
        std::string(primitives::kind_name(kind)).c_str(), p.class_id, p.points, p.inliers,
        1000 * p.rms, p.confidence);
    if (const auto* t = std::get_if<primitives::TorusModel>(&p.model))
      std::printf(", R %.1f r %.1f mm", 1000 * t->major_radius, 1000 * t->minor_radius);
    if (const auto* c = std::get_if<primitives::CylinderModel>(&p.model))
      std::printf(", r %.1f mm", 1000 * c->radius);
    if (const auto* sp = std::get_if<primitives::SphereModel>(&p.model))
      std::printf(", r %.1f mm", 1000 * sp->radius);
    std::printf("\n");
  }
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int run_primitives_bench(const Arguments& args) {
  const LabelModel model = load_model(args.model);
  const RunContext context{args.threads, {}, {}};
  Figures predicted, truth;
  const bench::MatchOptions match_options;
  InstanceFigures predicted_instances, truth_instances, cgal_instances;
  double label_seconds = 0;  // label_cloud end to end: normals, descriptors, CRF, primitives
  [[maybe_unused]] std::size_t cgal_degenerate = 0;
  for (int s = 0; s < args.scenes; ++s) {
    synth::GenerateOptions options;
    options.seed = args.first_seed + std::uint64_t(s);
    synth::Generated g = synth::generate(options);
    const std::vector<std::uint32_t> true_labels = g.cloud.labels;
    const FloatField* object = g.cloud.find_field("object");
    if (!object) throw std::runtime_error("the synthetic cloud has no object field");
    const FloatField objects = *object;
    const std::vector<TrueSurface> surfaces = true_surfaces(g.scene);
    std::vector<std::size_t> true_points(surfaces.size(), 0);
    for (std::size_t i = 0; i < true_labels.size(); ++i)
      for (std::size_t t = 0; t < surfaces.size(); ++t)
        if (int(objects.values[i]) == surfaces[t].object && true_labels[i] == surfaces[t].class_id)
          ++true_points[t];

    std::vector<synth::TruePrimitive> instances = synth::true_primitives(g.scene);
    synth::count_points_on(instances, g.cloud, match_options.tolerance);

    pipeline::LabelingOptions labeling;
    labeling.want_primitives = true;
    const auto label_start = std::chrono::steady_clock::now();
    const pipeline::LabelingResult result =
        pipeline::label_cloud(model, g.cloud, labeling, context);
    label_seconds += seconds_since(label_start);
    predicted.seconds += result.seconds.primitives;
    score(*result.primitives, surfaces, true_points, objects, predicted);
    predicted_instances.seconds += result.seconds.primitives;
    add_match(bench::match_instances(*result.primitives, g.cloud.xyz, objects.values, instances,
                                     match_options),
              instances, match_options, predicted_instances);

    const auto start = std::chrono::steady_clock::now();
    const primitives::PrimitiveSet from_truth = primitives::fit_primitives(
        g.cloud.xyz, g.cloud.normals, true_labels, labeling.primitives, context);
    truth.seconds += seconds_since(start);
    truth_instances.seconds += seconds_since(start);
    score(from_truth, surfaces, true_points, objects, truth);
    const bench::InstanceMatch truth_match =
        bench::match_instances(from_truth, g.cloud.xyz, objects.values, instances, match_options);
    add_match(truth_match, instances, match_options, truth_instances);
    if (args.explain_misses) {
      explain_misses("true labels", options.seed, from_truth, g.cloud.xyz, objects, instances,
                     truth_match, match_options);
      explain_misses("predicted", options.seed, *result.primitives, g.cloud.xyz, objects, instances,
                     bench::match_instances(*result.primitives, g.cloud.xyz, objects.values,
                                            instances, match_options),
                     match_options);
    }
#ifdef PRIMLABEL_HAVE_CGAL
    // The same points with primlabel's normals (label_cloud left them in the cloud).
    auto cgal_parameters = bench::CgalRansacParameters::for_spacing(result.point_spacing);
    cgal_parameters.probability = args.cgal_probability;
    cgal_parameters.cluster_epsilon *= args.cgal_cluster_spacings / 4;
    const bench::CgalDetections cgal =
        bench::detect_with_cgal(g.cloud.xyz, g.cloud.normals, cgal_parameters);
    cgal_instances.seconds += cgal.seconds;
    cgal_degenerate += cgal.degenerate;
    add_match(
        bench::match_instances(cgal.set, g.cloud.xyz, objects.values, instances, match_options),
        instances, match_options, cgal_instances);
    std::printf(
        "seed %llu: CGAL Efficient RANSAC %zu shapes (%zu degenerate, reported as their limit) "
        "in %.0f ms; epsilon %.1f mm, normals within %.0f deg, cluster epsilon %.1f mm, min "
        "points %zu\n",
        static_cast<unsigned long long>(options.seed), cgal.set.primitives.size(), cgal.degenerate,
        1000 * cgal.seconds, 1000 * cgal_parameters.epsilon,
        std::acos(cgal_parameters.normal_threshold) * 180 / M_PI,
        1000 * cgal_parameters.cluster_epsilon, cgal_parameters.min_points);
#endif
    std::printf(
        "seed %llu: %zu points, %s; %zu primitives from predicted labels in %.0f ms "
        "(segments %.0f ms)\n",
        static_cast<unsigned long long>(options.seed), g.cloud.size(),
        synth::describe_objects(g.scene).c_str(), result.primitives->primitives.size(),
        1000 * result.seconds.primitives, 1000 * result.primitives->segment_seconds);
  }
  print("predicted labels", predicted, args.scenes);
  print("true labels", truth, args.scenes);
  std::printf(
      "instances (true primitives with >= %zu scan points of their own, planes included):\n",
      match_options.min_true_points);
  print_instances("primlabel, predicted", predicted_instances, args.scenes);
  print_instances("primlabel, true labels", truth_instances, args.scenes);
  std::printf("%-22s label_cloud end to end %.0f ms/scan (%d threads)\n", "",
              1000 * label_seconds / args.scenes, args.threads);
  json::Json line = {
      {"scenes", args.scenes},
      {"threads", args.threads},
      {"predicted_labels", figures_json(predicted, args.scenes)},
      {"true_labels", figures_json(truth, args.scenes)},
      {"instances_predicted_labels", instance_json(predicted_instances, args.scenes)},
      {"instances_true_labels", instance_json(truth_instances, args.scenes)},
      {"label_cloud_ms_per_scan", json::rounded(1000 * label_seconds / args.scenes, "%.1f")}};
#ifdef PRIMLABEL_HAVE_CGAL
  print_instances("CGAL Efficient RANSAC", cgal_instances, args.scenes);
  const double fit_speedup = cgal_instances.seconds / predicted_instances.seconds;
  const double end_to_end_speedup = cgal_instances.seconds / label_seconds;
  std::printf(
      "%-22s CGAL is single-threaded; primlabel on %d threads is %.1fx faster fitting (%.1fx "
      "with labeling end to end, normals excluded from CGAL's time)\n",
      "", args.threads, fit_speedup, end_to_end_speedup);
  line["instances_cgal"] = instance_json(cgal_instances, args.scenes);
  line["cgal_degenerate_shapes"] = cgal_degenerate;
  line["cgal_over_primlabel_fit_time"] = json::rounded(fit_speedup, "%.2f");
  line["cgal_over_primlabel_label_cloud_time"] = json::rounded(end_to_end_speedup, "%.2f");
#else
  std::printf(
      "CGAL not found at build time: no Efficient RANSAC comparison (install libcgal-dev)\n");
  line["instances_cgal"] = nullptr;
#endif
  std::printf("%s\n", json::dump(line).c_str());
  return kExitOk;
}

}  // namespace

namespace primlabel::bench {

BenchCommand add_primitives_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "primitives",
      "Fitted primitive instances on held-out synthetic LMS400 scenes vs the true shapes.");
  cmd->add_option("--model", args->model, "LMS400 model file (primlabel-train -o)")->required();
  cmd->add_option("--scenes", args->scenes, "held-out scenes (seeds 3000..)")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--first-seed", args->first_seed, "seed of the first scene");
  cmd->add_option("--threads", args->threads, "worker threads")->check(CLI::PositiveNumber);
  cmd->add_option(
         "--cgal-probability", args->cgal_probability,
         "CGAL Efficient RANSAC: chance of missing the largest shape (lower: longer search)")
      ->check(CLI::Range(1e-6, 1.0))
      ->capture_default_str();
  cmd->add_option("--cgal-cluster-spacings", args->cgal_cluster_spacings,
                  "CGAL Efficient RANSAC: cluster epsilon in median point spacings")
      ->check(CLI::Range(0.5, 100.0))
      ->capture_default_str();
  cmd->add_flag("--explain-misses", args->explain_misses,
                "print, per unmatched true primitive, the detections with points on it, and the "
                "detections no true primitive took");
  return {cmd, [args] { return run_primitives_bench(*args); }};
}

}  // namespace primlabel::bench
