// primlabel-bench can-radii: on real mOSD scenes, the radius of each can as the labeling service
// would report it against the fitted ground truth (synth/fitted_truth.hpp). Each scene is
// labeled table-top only with objects and primitives (what a robot asks for); each object segment
// the truth fits as a cylinder is matched to the table-top object holding most of its points,
// and that object's largest cylinder primitive gives our radius. Prints a row per can (scene,
// segment, truth radius and fit residual, ours, the difference), then the spread of the truth
// radius across scenes for cans that look alike (truth radius within 3 mm and length within
// 1 cm: most likely the same can seen again), and the summary. Last line: JSON.
//
//   primlabel-bench can-radii --model build/models/tabletop-kinect/1/model.plm \
//       ../shared/data/mosd/learn*.pcd

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>

#include "bench_commands.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/synth/fitted_truth.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string model;
  std::vector<std::string> scenes;
  int threads = 2;
};

struct CanRow {
  std::string scene;
  int segment = 0;
  std::string kind;  // upright-cylinder, lying-cylinder
  double truth_radius = 0, truth_length = 0, truth_rms = 0;
  std::size_t truth_points = 0;
  std::uint32_t object = tabletop::kNoObject;  // our matched object
  double overlap = 0;                          // share of the segment's points in it
  std::optional<double> radius;                // our largest cylinder primitive's
  std::size_t primitive_points = 0;
  double confidence = 0;
  std::string missing;  // why there is no radius
};

// printf of one number, "-" when it is not finite.
std::string format(double value, const char* spec) {
  if (!std::isfinite(value)) return "-";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, spec, value);
  return buffer;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double spread(const std::vector<double>& v) {  // sample standard deviation
  if (v.size() < 2) return NAN;
  double mean = 0;
  for (double x : v) mean += x;
  mean /= double(v.size());
  double sum = 0;
  for (double x : v) sum += (x - mean) * (x - mean);
  return std::sqrt(sum / double(v.size() - 1));
}

std::vector<CanRow> scene_cans(const LabelModel& model, const std::string& path,
                               const RunContext& context) {
  PointCloud cloud = read_cloud(path);
  if (!cloud.has_labels()) throw std::runtime_error(path + ": no label field");
  const std::vector<int> segments = synth::mosd_segments(cloud.labels);
  const synth::ObjectTruth truth = synth::fit_object_truth(cloud, segments, {}, context);

  pipeline::LabelingOptions options;
  options.tabletop_only = true;
  options.want_objects = true;
  options.want_primitives = true;
  const pipeline::LabelingResult result = pipeline::label_cloud(model, cloud, options, context);
  const tabletop::TabletopObjects& objects = *result.objects;
  const auto& primitives = result.primitives->primitives;

  std::vector<CanRow> rows;
  for (const synth::FittedObject& fitted : truth.objects) {
    if (fitted.kind != synth::FittedKind::kUprightCylinder &&
        fitted.kind != synth::FittedKind::kLyingCylinder)
      continue;
    CanRow row;
    row.scene = std::filesystem::path(path).stem().string();
    row.segment = fitted.segment;
    row.kind = std::string(synth::fitted_kind_name(fitted.kind));
    row.truth_radius = fitted.size.x();
    row.truth_length = fitted.size.y();
    row.truth_rms = fitted.rms;
    row.truth_points = fitted.points;
    std::map<std::uint32_t, std::size_t> votes;
    std::size_t segment_points = 0;
    for (std::size_t i = 0; i < segments.size(); ++i)
      if (segments[i] == fitted.segment) {
        ++segment_points;
        const std::uint32_t id = objects.point_object[i];
        if (id != tabletop::kNoObject && id != tabletop::kTableObject) ++votes[id];
      }
    const auto best = std::max_element(votes.begin(), votes.end(),
                                       [](auto& a, auto& b) { return a.second < b.second; });
    if (best == votes.end()) {
      row.missing = "no object";
      rows.push_back(row);
      continue;
    }
    row.object = best->first;
    row.overlap = double(best->second) / double(std::max<std::size_t>(1, segment_points));
    const tabletop::TabletopObject& object = objects.objects[row.object - 1];
    for (std::uint32_t s : object.primitive_ids) {
      const auto* cylinder = std::get_if<primitives::CylinderModel>(&primitives[s].model);
      if (!cylinder || primitives[s].points <= row.primitive_points) continue;
      row.radius = cylinder->radius;
      row.primitive_points = primitives[s].points;
      row.confidence = primitives[s].confidence;
    }
    if (!row.radius) row.missing = "no cylinder primitive";
    rows.push_back(row);
  }
  return rows;
}

int run_can_radii_bench(const Arguments& args) {
  const LabelModel model = load_model(args.model);
  const RunContext context{args.threads, {}, {}};
  std::vector<CanRow> rows;
  for (const std::string& scene : args.scenes) {
    std::vector<CanRow> found = scene_cans(model, scene, context);
    rows.insert(rows.end(), found.begin(), found.end());
    std::fprintf(stderr, "%s: %zu cans\n", scene.c_str(), found.size());
  }
  std::printf("%-8s %4s %-16s %7s %7s %6s %6s %4s %5s %7s %6s %5s %7s\n", "scene", "seg", "truth",
              "r_mm", "len_mm", "rms_mm", "points", "obj", "share", "ours_mm", "diff", "conf",
              "cyl_pts");
  std::vector<double> errors, signed_errors, truth_rms;
  json::Json list = json::Json::array();
  for (const CanRow& r : rows) {
    const double diff = r.radius ? 1000 * (*r.radius - r.truth_radius) : NAN;
    std::printf("%-8s %4d %-16s %7.1f %7.1f %6.2f %6zu %4s %5.2f %7s %6s %5.2f %7zu %s\n",
                r.scene.c_str(), r.segment, r.kind.c_str(), 1000 * r.truth_radius,
                1000 * r.truth_length, 1000 * r.truth_rms, r.truth_points,
                r.object == tabletop::kNoObject ? "-" : std::to_string(r.object).c_str(), r.overlap,
                format(r.radius ? 1000 * *r.radius : NAN, "%.1f").c_str(),
                format(diff, "%+.1f").c_str(), r.confidence, r.primitive_points, r.missing.c_str());
    truth_rms.push_back(1000 * r.truth_rms);
    if (r.radius) {
      errors.push_back(std::abs(diff));
      signed_errors.push_back(diff);
    }
    list.push_back(
        {{"scene", r.scene},
         {"segment", r.segment},
         {"truth_kind", r.kind},
         {"truth_radius_mm", json::rounded(1000 * r.truth_radius, "%.2f")},
         {"truth_length_mm", json::rounded(1000 * r.truth_length, "%.1f")},
         {"truth_rms_mm", json::rounded(1000 * r.truth_rms, "%.2f")},
         {"object", r.object == tabletop::kNoObject ? json::Json() : json::Json(r.object)},
         {"radius_mm", r.radius ? json::rounded(1000 * *r.radius, "%.2f") : json::Json()},
         {"confidence", json::rounded(r.confidence, "%.3f")},
         {"missing", r.missing}});
  }
  // Cans that look alike across scenes: greedy groups in order of truth radius.
  std::vector<const CanRow*> order;
  for (const CanRow& r : rows) order.push_back(&r);
  std::sort(order.begin(), order.end(),
            [](auto* a, auto* b) { return a->truth_radius < b->truth_radius; });
  std::vector<std::vector<const CanRow*>> groups;
  for (const CanRow* r : order) {
    bool placed = false;
    for (auto& g : groups)
      if (std::abs(r->truth_radius - g.front()->truth_radius) <= 0.003 &&
          std::abs(r->truth_length - g.front()->truth_length) <= 0.01) {
        g.push_back(r);
        placed = true;
        break;
      }
    if (!placed) groups.push_back({r});
  }
  std::printf("\nlook-alike groups (truth radius within 3 mm, length within 1 cm of the first):\n");
  std::printf("%5s %9s %9s %10s %9s %10s %s\n", "cans", "truth_r", "truth_sd", "ours_r", "ours_sd",
              "mean_diff", "scenes");
  json::Json group_list = json::Json::array();
  for (const auto& g : groups) {
    std::vector<double> truth_r, ours_r, diffs;
    std::string scenes;
    for (const CanRow* r : g) {
      truth_r.push_back(1000 * r->truth_radius);
      if (r->radius) {
        ours_r.push_back(1000 * *r->radius);
        diffs.push_back(1000 * (*r->radius - r->truth_radius));
      }
      scenes += (scenes.empty() ? "" : ",") + r->scene;
    }
    const auto mean = [](const std::vector<double>& v) {
      double s = 0;
      for (double x : v) s += x;
      return v.empty() ? NAN : s / double(v.size());
    };
    std::printf("%5zu %9.1f %9.2f %10.1f %9.2f %10.2f %s\n", g.size(), mean(truth_r),
                spread(truth_r), mean(ours_r), spread(ours_r), mean(diffs), scenes.c_str());
    group_list.push_back({{"cans", g.size()},
                          {"truth_radius_mm", json::rounded(mean(truth_r), "%.2f")},
                          {"truth_sd_mm", json::rounded(spread(truth_r), "%.2f")},
                          {"radius_mm", json::rounded(mean(ours_r), "%.2f")},
                          {"sd_mm", json::rounded(spread(ours_r), "%.2f")},
                          {"mean_diff_mm", json::rounded(mean(diffs), "%.2f")}});
  }
  std::printf(
      "\n%zu cans (truth cylinders) in %zu scenes; %zu with a radius from their object; median "
      "|ours - truth| %.2f mm, median signed %.2f mm; median truth fit rms %.2f mm\n",
      rows.size(), args.scenes.size(), errors.size(), median(errors), median(signed_errors),
      median(truth_rms));
  std::printf("%s\n",
              json::dump(json::Json{{"cans", std::move(list)},
                                    {"groups", std::move(group_list)},
                                    {"median_abs_error_mm", json::rounded(median(errors), "%.3f")},
                                    {"median_signed_error_mm",
                                     json::rounded(median(signed_errors), "%.3f")},
                                    {"with_radius", errors.size()},
                                    {"cans_total", rows.size()}})
                  .c_str());
  return 0;
}

}  // namespace

namespace primlabel::bench {

BenchCommand add_can_radii_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "can-radii",
      "Can radii on real mOSD scenes: the service's fitted cylinders vs the fitted truth.");
  cmd->add_option("--model", args->model, "Kinect model file (tabletop-kinect)")->required();
  cmd->add_option("SCENE", args->scenes, "mOSD scenes (.pcd with the label field)")->required();
  cmd->add_option("--threads", args->threads, "worker threads")->check(CLI::PositiveNumber);
  return {cmd, [args] { return run_can_radii_bench(*args); }};
}

}  // namespace primlabel::bench
