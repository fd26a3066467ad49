// primlabel-bench-primitives: fitted primitive instances on held-out synthetic LMS400 scenes
// against the shapes the generator placed. Each scene is labeled by a model, and its primitives
// are fitted twice: from the predicted labels (what the service returns) and from the true
// labels (the fit alone). A true surface is an object's curved part (can or mug side, the inside
// of a mug, a ball, a bowl's outside or inside, a ring) with 50 or more truly labeled points; it
// is found when a primitive of its model and class has most of its points on that object. Prints
// a row per scene, the radius and axis errors of the found surfaces and the time to fit; last
// line: JSON.
//
//   primlabel-bench-primitives --model build/models/tabletop-lms400/1/model.plm --scenes 4

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>

#include "primlabel/build_version.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/primitives/fit_primitives.hpp"
#include "primlabel/synth/generate.hpp"
#include "primlabel/synth/true_primitives.hpp"

namespace {

using namespace primlabel;
using primitives::PrimitiveKind;
using Vec3d = Eigen::Vector3d;

struct Arguments {
  std::string model;
  int scenes = 4, threads = 2;
  std::uint64_t first_seed = 3000;  // the test set's seeds (synth::SceneSet::kTest)
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

double axis_angle_deg(const Vec3d& a, const Vec3d& b) {
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180 / M_PI;
}

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

int run(const Arguments& args) {
  const LabelModel model = load_model(args.model);
  const RunContext context{args.threads, {}, {}};
  Figures predicted, truth;
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

    pipeline::LabelingOptions labeling;
    labeling.want_primitives = true;
    const pipeline::LabelingResult result =
        pipeline::label_cloud(model, g.cloud, labeling, context);
    predicted.seconds += result.primitive_seconds;
    score(*result.primitives, surfaces, true_points, objects, predicted);

    const auto start = std::chrono::steady_clock::now();
    const primitives::PrimitiveSet from_truth = primitives::fit_primitives(
        g.cloud.xyz, g.cloud.normals, true_labels, labeling.primitives, context);
    truth.seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    score(from_truth, surfaces, true_points, objects, truth);
    std::printf(
        "seed %llu: %zu points, %s; %zu primitives from predicted labels in %.0f ms "
        "(segments %.0f ms)\n",
        static_cast<unsigned long long>(options.seed), g.cloud.size(),
        synth::describe_objects(g.scene).c_str(), result.primitives->primitives.size(),
        1000 * result.primitive_seconds, 1000 * result.primitives->segment_seconds);
  }
  print("predicted labels", predicted, args.scenes);
  print("true labels", truth, args.scenes);
  const json::Json line = {{"scenes", args.scenes},
                           {"threads", args.threads},
                           {"predicted_labels", figures_json(predicted, args.scenes)},
                           {"true_labels", figures_json(truth, args.scenes)}};
  std::printf("%s\n", json::dump(line).c_str());
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Fitted primitive instances on held-out synthetic LMS400 scenes vs the true shapes."};
  app.set_version_flag("--version", primlabel::version_line("primlabel-bench-primitives"));
  app.name("primlabel-bench-primitives");
  Arguments args;
  app.add_option("--model", args.model, "LMS400 model file (primlabel-train -o)")->required();
  app.add_option("--scenes", args.scenes, "held-out scenes (seeds 3000..)")
      ->check(CLI::Range(1, 100));
  app.add_option("--first-seed", args.first_seed, "seed of the first scene");
  app.add_option("--threads", args.threads, "worker threads")->check(CLI::PositiveNumber);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "primlabel-bench-primitives: usage error: %s\n", e.what());
    return primlabel::kExitUsage;
  }
  try {
    return run(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-bench-primitives: error: %s\n", e.what());
    return primlabel::kExitFailure;
  }
}
