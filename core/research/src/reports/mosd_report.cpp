// mOSD report: label a real scene, count its table points labeled plane, draw it.

#include "primlabel/research/mosd_report.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
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

double MosdSceneReport::plane_share() const { return share(table_plane, table_points); }
double MosdSceneReport::object_plane_share() const { return share(object_plane, object_points); }
double MosdReport::plane_share() const { return share(table_plane, table_points); }

MosdSceneReport report_mosd_scene(const LabelModel& model, const std::string& path,
                                  const std::string& png_path,
                                  const pipeline::LabelingOptions& options,
                                  const RunContext& context) {
  PointCloud cloud = read_cloud(path);
  if (!cloud.has_labels())
    throw std::runtime_error(path + ": no label field (an mOSD scene labels table and objects)");
  const std::vector<std::uint32_t> segments = cloud.labels;
  const pipeline::LabelingResult result = pipeline::label_cloud(model, cloud, options, context);

  MosdSceneReport report;
  report.file = path;
  report.feature_seconds = result.feature_seconds;
  report.inference_seconds = result.inference_seconds;
  report.table_predicted.assign(kPrimitiveClassCount, 0);
  const std::uint32_t plane = class_id(PrimitiveClass::kPlane);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!is_finite(cloud.xyz[i])) continue;
    ++report.points;
    const bool is_plane = result.labels[i] == plane;
    if (is_mosd_table_label(segments[i])) {
      ++report.table_points;
      report.table_plane += is_plane;
      if (result.labels[i] < kPrimitiveClassCount) ++report.table_predicted[result.labels[i]];
    } else if (is_mosd_object_label(segments[i])) {
      ++report.object_points;
      report.object_plane += is_plane;
    }
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
  }
  return report;
}

std::string mosd_report_text(const MosdReport& report) {
  std::string out = format("%-28s %9s %12s %12s %13s %8s\n", "scene", "points", "table pts",
                           "table plane", "objects plane", "s");
  for (const MosdSceneReport& s : report.scenes)
    out += format("%-28s %9llu %12llu %11.2f%% %12.2f%% %8.2f\n",
                  std::filesystem::path(s.file).filename().string().c_str(),
                  static_cast<unsigned long long>(s.points),
                  static_cast<unsigned long long>(s.table_points), 100.0 * s.plane_share(),
                  100.0 * s.object_plane_share(), s.feature_seconds + s.inference_seconds);
  out += format("%-28s %9s %12llu %11.2f%%\n", "overall", "",
                static_cast<unsigned long long>(report.table_points), 100.0 * report.plane_share());
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
                      {"object_points", s.object_points},
                      {"object_plane_share", json_number(s.object_plane_share())},
                      {"table_predicted", std::move(predicted)},
                      {"seconds", json_number(s.feature_seconds + s.inference_seconds)},
                      {"png", s.png}});
  }
  const json::Json out = {{"scenes", std::move(scenes)},
                          {"table_points", report.table_points},
                          {"table_plane", report.table_plane},
                          {"plane_share", json_number(report.plane_share())}};
  return json::dump(out) + "\n";
}

}  // namespace primlabel::research
