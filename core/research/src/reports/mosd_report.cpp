// mOSD report: label a real scene, count its table points labeled plane, draw it.

#include "primlabel/research/mosd_report.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/render/colorize.hpp"
#include "primlabel/render/render.hpp"

namespace primlabel::research {

namespace {

double share(std::uint64_t part, std::uint64_t whole) {
  return whole ? double(part) / double(whole) : NAN;
}

std::string format(const char* fmt, auto... args) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, fmt, args...);
  return buffer;
}

json::Json json_number(double v) { return json::rounded(v, "%.6f"); }

// Per point: whether it is a table point within kContactBand of an object point.
std::vector<std::uint8_t> contact_band(const PointCloud& cloud,
                                       const std::vector<std::uint32_t>& segments,
                                       const RunContext& context) {
  std::vector<Vec3f> objects;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (is_mosd_object_label(segments[i]) && is_finite(cloud.xyz[i]))
      objects.push_back(cloud.xyz[i]);
  std::vector<std::uint8_t> near(cloud.size(), 0);
  if (objects.empty()) return near;
  const NeighborSearch search(objects, context.stop);
  NeighborList nearest;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!is_mosd_table_label(segments[i])) continue;
    search.find(cloud.xyz[i], Neighborhood::Knn(1), nearest);
    near[i] = nearest.size() && nearest.sq_dists[0] <= kContactBand * kContactBand;
  }
  return near;
}

double mean(const std::vector<MosdSceneReport>& scenes, double (MosdSceneReport::*share)() const) {
  double sum = 0;
  int n = 0;
  for (const MosdSceneReport& s : scenes)
    if (const double v = (s.*share)(); std::isfinite(v)) sum += v, ++n;
  return n ? sum / n : NAN;
}

void render_labels(const PointCloud& cloud, const std::vector<std::uint32_t>& labels,
                   const std::string& title, const std::string& path) {
  PointCloud labeled;
  labeled.xyz = cloud.xyz;
  labeled.width = cloud.width;
  labeled.height = cloud.height;
  labeled.viewpoint = cloud.viewpoint;
  labeled.labels = labels;
  const Coloring coloring = color_by_class(labeled, ClassMap::taxonomy());
  RenderOptions options;
  options.width = 960;
  options.height = 720;
  options.view = RenderView::kSensor;
  options.title = title;
  options.legend = coloring.legend;
  render_png(labeled, coloring.rgb, options, path);
}

}  // namespace

json::Json fitted_object_json(const FittedObject& o) {
  const Eigen::Vector3d at = o.table_from_local.translation();
  return {{"segment", o.segment},
          {"kind", std::string(fitted_kind_name(o.kind))},
          {"points", o.points},
          {"inlier_share", json_number(o.inlier_share())},
          {"rms", json::rounded(o.rms, "%.5f")},
          {"bound", json::rounded(o.bound, "%.5f")},
          {"max_rms", json::rounded(o.max_rms, "%.5f")},
          {"on_table", o.on_table},
          {"faces", o.faces},
          {"size",
           {json::rounded(o.size.x(), "%.4f"), json::rounded(o.size.y(), "%.4f"),
            json::rounded(o.size.z(), "%.4f")}},
          {"at",
           {json::rounded(at.x(), "%.4f"), json::rounded(at.y(), "%.4f"),
            json::rounded(at.z(), "%.4f")}},
          {"box_cost", json_number(o.box_cost)},
          {"cylinder_cost", json_number(o.cylinder_cost)}};
}

json::Json object_truth_json(const MosdObjectTruth& t, bool with_objects) {
  json::Json out = {{"boxes", t.count(FittedKind::kBox)},
                    {"upright_cylinders", t.count(FittedKind::kUprightCylinder)},
                    {"lying_cylinders", t.count(FittedKind::kLyingCylinder)},
                    {"unfitted", t.count(FittedKind::kUnfitted)},
                    {"object_points", t.object_points},
                    {"truth_points", t.truth_points}};
  if (t.scores.total()) out["scores"] = confusion_classes_json(t.scores);
  if (!t.truth_file.empty()) out["truth_file"] = t.truth_file;
  if (with_objects) {
    json::Json objects = json::Json::array();
    for (const FittedObject& o : t.objects) objects.push_back(fitted_object_json(o));
    out["objects"] = std::move(objects);
  }
  return out;
}

double MosdSceneReport::plane_share() const { return share(table_plane, table_points); }
double MosdSceneReport::away_plane_share() const { return share(table_away_plane, table_away); }
double MosdSceneReport::object_plane_share() const { return share(object_plane, object_points); }
double MosdReport::plane_share() const { return share(table_plane, table_points); }
double MosdReport::away_plane_share() const { return share(table_away_plane, table_away); }
double MosdReport::mean_plane_share() const { return mean(scenes, &MosdSceneReport::plane_share); }
double MosdReport::mean_away_plane_share() const {
  return mean(scenes, &MosdSceneReport::away_plane_share);
}

MosdSceneReport report_mosd_scene(const LabelModel& model, const std::string& path,
                                  const std::string& png_path,
                                  const pipeline::LabelingOptions& options,
                                  const RunContext& context, const MosdTruthRequest& truth) {
  PointCloud cloud = read_cloud(path);
  if (!cloud.has_labels())
    throw std::runtime_error(path + ": no label field (an mOSD scene labels table and objects)");
  const std::vector<std::uint32_t> segments = cloud.labels;
  std::optional<MosdObjectTruth> object_truth;
  std::vector<std::uint32_t> truth_labels;
  if (truth.enabled) {
    try {
      object_truth = fit_mosd_truth(cloud, truth, context, &truth_labels);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(path + ": " + e.what());
    }
  }
  const std::vector<std::uint8_t> near_object = contact_band(cloud, segments, context);
  const pipeline::LabelingResult result = pipeline::label_cloud(model, cloud, options, context);

  MosdSceneReport report;
  report.file = path;
  report.feature_seconds = result.seconds.normals + result.seconds.descriptors;
  report.inference_seconds = result.seconds.graph + result.seconds.inference;
  report.table_predicted.assign(kPrimitiveClassCount, 0);
  const std::uint32_t plane = class_id(PrimitiveClass::kPlane);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!is_finite(cloud.xyz[i])) continue;
    ++report.points;
    const bool is_plane = result.labels[i] == plane;
    if (is_mosd_table_label(segments[i])) {
      ++report.table_points;
      report.table_plane += is_plane;
      if (!near_object[i]) ++report.table_away, report.table_away_plane += is_plane;
      if (result.labels[i] < kPrimitiveClassCount) ++report.table_predicted[result.labels[i]];
    } else if (is_mosd_object_label(segments[i])) {
      ++report.object_points;
      report.object_plane += is_plane;
    }
  }
  if (object_truth) {
    add_object_points(object_truth->scores, mosd_segments(segments), truth_labels, result.labels);
    report.object_truth = std::move(object_truth);
  }
  if (!png_path.empty()) {
    const std::string scene = std::filesystem::path(path).stem().string();
    render_labels(
        cloud, result.labels,
        format("%s: %.1f%% of table points plane", scene.c_str(), 100.0 * report.plane_share()),
        png_path);
    report.png = png_path;
  }
  return report;
}

MosdReport summarize_mosd(std::vector<MosdSceneReport> scenes) {
  MosdReport report;
  report.scenes = std::move(scenes);
  for (const MosdSceneReport& s : report.scenes) {
    report.table_points += s.table_points;
    report.table_plane += s.table_plane;
    report.table_away += s.table_away;
    report.table_away_plane += s.table_away_plane;
    if (!s.object_truth) continue;
    if (!report.object_truth) report.object_truth.emplace();
    MosdObjectTruth& all = *report.object_truth;
    all.objects.insert(all.objects.end(), s.object_truth->objects.begin(),
                       s.object_truth->objects.end());
    all.object_points += s.object_truth->object_points;
    all.truth_points += s.object_truth->truth_points;
    all.scores.add(s.object_truth->scores);
  }
  return report;
}

std::string mosd_report_text(const MosdReport& report) {
  std::string out = format("%-28s %9s %12s %12s %12s %13s %8s\n", "scene", "points", "table pts",
                           "table plane", "away plane", "objects plane", "s");
  for (const MosdSceneReport& s : report.scenes)
    out += format("%-28s %9llu %12llu %11.2f%% %11.2f%% %12.2f%% %8.2f\n",
                  std::filesystem::path(s.file).filename().string().c_str(),
                  static_cast<unsigned long long>(s.points),
                  static_cast<unsigned long long>(s.table_points), 100.0 * s.plane_share(),
                  100.0 * s.away_plane_share(), 100.0 * s.object_plane_share(),
                  s.feature_seconds + s.inference_seconds);
  out += format("%-28s %9s %12llu %11.2f%% %11.2f%%\n", "overall", "",
                static_cast<unsigned long long>(report.table_points), 100.0 * report.plane_share(),
                100.0 * report.away_plane_share());
  out += format("%-28s %9s %12s %11.2f%% %11.2f%%   (away: > %.0f mm from any object point)\n",
                "mean of the scenes", "", "", 100.0 * report.mean_plane_share(),
                100.0 * report.mean_away_plane_share(), 1000.0 * kContactBand);
  if (!report.object_truth) return out;
  out += format("\nobject truth (fitted)       %5s %5s %5s %5s %12s %12s %9s\n", "box", "cyl|",
                "cyl-", "none", "object pts", "scored pts", "accuracy");
  auto truth_row = [&](const std::string& label, const MosdObjectTruth& t) {
    return format("%-27s %5zu %5zu %5zu %5zu %12llu %12llu %8.2f%%\n", label.c_str(),
                  t.count(FittedKind::kBox), t.count(FittedKind::kUprightCylinder),
                  t.count(FittedKind::kLyingCylinder), t.count(FittedKind::kUnfitted),
                  static_cast<unsigned long long>(t.object_points),
                  static_cast<unsigned long long>(t.truth_points), 100.0 * t.scores.accuracy());
  };
  for (const MosdSceneReport& s : report.scenes)
    if (s.object_truth)
      out += truth_row(std::filesystem::path(s.file).filename().string(), *s.object_truth);
  out += truth_row("overall", *report.object_truth);
  out += "the model on the object points, against the fitted truth:\n";
  const crf::ConfusionMatrix& m = report.object_truth->scores;
  out += format("  %-16s %10s %9s %9s\n", "class", "points", "recall", "precision");
  for (int k = 0; k < m.num_classes(); ++k) {
    const crf::ClassScores c = m.scores(k);
    if (!c.support && !(c.precision >= 0)) continue;
    const auto cls = class_from_id(m.class_ids()[k]);
    out += format("  %-16s %10llu %8.1f%% %8.1f%%\n", std::string(name(*cls)).c_str(),
                  static_cast<unsigned long long>(c.support), 100 * c.recall, 100 * c.precision);
  }
  return out;
}

std::string mosd_report_json(const MosdReport& report) {
  json::Json scenes = json::Json::array();
  for (const MosdSceneReport& s : report.scenes) {
    json::Json predicted = json::Json::object();
    for (std::uint32_t id = 0; id < s.table_predicted.size(); ++id) {
      if (!s.table_predicted[id]) continue;
      const auto c = class_from_id(id);
      predicted[c ? std::string(name(*c)) : std::to_string(id)] = s.table_predicted[id];
    }
    scenes.push_back({{"file", s.file},
                      {"points", s.points},
                      {"table_points", s.table_points},
                      {"table_plane", s.table_plane},
                      {"plane_share", json_number(s.plane_share())},
                      {"table_away", s.table_away},
                      {"away_plane_share", json_number(s.away_plane_share())},
                      {"object_points", s.object_points},
                      {"object_plane_share", json_number(s.object_plane_share())},
                      {"table_predicted", std::move(predicted)},
                      {"seconds", json_number(s.feature_seconds + s.inference_seconds)},
                      {"png", s.png}});
    if (s.object_truth) scenes.back()["object_truth"] = object_truth_json(*s.object_truth, true);
  }
  json::Json out = {{"scenes", std::move(scenes)},
                    {"table_points", report.table_points},
                    {"table_plane", report.table_plane},
                    {"plane_share", json_number(report.plane_share())},
                    {"mean_plane_share", json_number(report.mean_plane_share())},
                    {"table_away", report.table_away},
                    {"away_plane_share", json_number(report.away_plane_share())},
                    {"mean_away_plane_share", json_number(report.mean_away_plane_share())}};
  if (report.object_truth) out["object_truth"] = object_truth_json(*report.object_truth, false);
  return json::dump(out) + "\n";
}

}  // namespace primlabel::research
