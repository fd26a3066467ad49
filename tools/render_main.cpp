// primlabel-render: a PNG picture of a point cloud, coloured by label, segment, rgb or a value.
//
//   primlabel-render scene.pcd -o scene.png                       # by label, with a legend
//   primlabel-render learn0.pcd -o learn0.png --field label --palette segments --view sensor
//   primlabel-render features.pcd -o curvature.png --field curvature --view top
//   primlabel-render labeled.pcd -o fits.png --primitives primitives.json   # fitted outlines
//   primlabel-render labeled.pcd -o objects.png --objects objects.json      # table-top boxes

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "primlabel/build_version.hpp"
#include "primlabel/cli/cli_common.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/overlays/object_overlays.hpp"
#include "primlabel/primitives/primitives_json.hpp"
#include "primlabel/render/colorize.hpp"
#include "primlabel/render/primitive_outlines.hpp"
#include "primlabel/render/render.hpp"
#include "primlabel/tabletop/objects_json.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string input, output, field, palette = "classes", classes, view = "auto", title;
  std::string primitives;  // JSON of primlabel label / primlabel-eval --primitives
  std::string objects;     // JSON of primlabel label / primlabel-eval --objects
  double min_confidence = 0;
  int width = 1024, height = 768, point_size = 1;
  bool no_legend = false, no_title = false;
};

class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string field_names(const PointCloud& cloud) {
  std::string out = "x y z";
  if (cloud.has_normals()) out += " normal_x normal_y normal_z";
  if (cloud.has_curvature()) out += " curvature";
  if (cloud.has_labels()) out += " label";
  if (cloud.has_rgba()) out += " rgb";
  for (const FloatField& f : cloud.fields) out += " " + f.name;
  return out;
}

Coloring coloring_for(const Arguments& args, const PointCloud& cloud, std::string& field) {
  if (field.empty()) field = cloud.has_labels() ? "label" : cloud.has_rgba() ? "rgb" : "z";
  if (field == "label") {
    if (!cloud.has_labels())
      throw RunError(args.input + " has no 'label' field (fields: " + field_names(cloud) + ")");
    if (args.palette == "segments") return color_by_segment(cloud);
    ClassMap map = ClassMap::taxonomy();
    if (!args.classes.empty()) {
      map = read_class_map(args.classes);
    } else {
      const CloudTags tags = read_cloud_tags(args.input);
      if (const auto it = tags.find("classes"); it != tags.end())
        map = class_map_from_tag(it->second);
    }
    return color_by_class(cloud, map);
  }
  if (field == "rgb" || field == "rgba") {
    if (!cloud.has_rgba())
      throw RunError(args.input + " has no 'rgb' field (fields: " + field_names(cloud) + ")");
    return color_by_rgb(cloud);
  }
  std::vector<float> values(cloud.size());
  const int axis = field == "x" ? 0 : field == "y" ? 1 : field == "z" ? 2 : -1;
  if (axis >= 0) {
    for (std::size_t i = 0; i < cloud.size(); ++i) values[i] = cloud.xyz[i][axis];
  } else if (field == "curvature" && cloud.has_curvature()) {
    values = cloud.curvature;
  } else if (const FloatField* f = cloud.find_field(field)) {
    for (std::size_t i = 0; i < cloud.size(); ++i) values[i] = f->row(i)[0];
  } else {
    throw RunError(args.input + " has no field '" + field + "' (fields: " + field_names(cloud) +
                   ")");
  }
  return color_by_value(values, field);
}

// The outlines of the primitives in `path`; a file that cannot be read or parsed is an input
// error naming it, not a usage error.
std::vector<Overlay> outlines_from(const std::string& path, double min_confidence) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RunError("cannot read primitives file '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  try {
    const std::vector<primitives::Primitive> fitted = primitives::parse_primitives_json(text.str());
    return primitive_outlines(fitted, {.min_confidence = min_confidence});
  } catch (const std::invalid_argument& e) {
    throw RunError(path + ": " + e.what());
  }
}

// The table's hull and every table-top object's axis-aligned box in `path` (objects_json.hpp), as
// primlabel label --png draws them (object_overlays.hpp).
std::vector<Overlay> object_boxes_from(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RunError("cannot read objects file '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  tabletop::TabletopObjects objects;
  try {
    objects = tabletop::parse_objects_json(text.str());
  } catch (const std::invalid_argument& e) {
    throw RunError(path + ": " + e.what());
  }
  return object_overlays(objects);
}

int run(const Arguments& args) {
  const PointCloud cloud = read_cloud(args.input);
  if (count_finite(cloud) == 0) throw RunError(args.input + ": no point has finite coordinates");
  std::string field = args.field;
  Coloring coloring = coloring_for(args, cloud, field);

  RenderOptions options;
  options.width = args.width;
  options.height = args.height;
  options.point_radius_px = args.point_size;
  options.view = args.view == "top"       ? RenderView::kTop
                 : args.view == "sensor"  ? RenderView::kSensor
                 : args.view == "oblique" ? RenderView::kOblique
                                          : natural_view(cloud);  // as primlabel label --png
  if (!args.no_title)
    options.title = !args.title.empty()
                        ? args.title
                        : std::filesystem::path(args.input).filename().string() + " - " + field +
                              " (" + std::to_string(count_finite(cloud)) + " points)";
  if (!args.no_legend) options.legend = std::move(coloring.legend);
  if (!args.primitives.empty())
    options.overlays = outlines_from(args.primitives, args.min_confidence);
  if (!args.objects.empty())
    for (Overlay& box : object_boxes_from(args.objects)) options.overlays.push_back(std::move(box));
  render_png(cloud, coloring.rgb, options, args.output);
  return cli::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Render a point cloud to PNG, coloured by label, segment, rgb or a field."};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-render"));
  app.name("primlabel-render");
  Arguments args;
  app.add_option("input", args.input, "input cloud (.pcd or .ply)")->required();
  // Only PNG is written: a .jpg name would get PNG bytes that viewers mistake or refuse.
  const CLI::Validator png_name(
      [](std::string& name) {
        std::string ext = std::filesystem::path(name).extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (ext == ".png") return std::string();
        return "'" + name + "': primlabel-render writes PNG only; name the output *.png";
      },
      "FILE.png");
  app.add_option("-o,--output", args.output, "output image (.png)")->required()->check(png_name);
  app.add_option("--field", args.field,
                 "colour by: label (default when present), rgb, x, y, z, curvature or any "
                 "float field (first value)");
  app.add_option("--palette", args.palette,
                 "for --field label: classes (taxonomy colours, default) or segments (a colour "
                 "per id, e.g. mOSD segment labels)")
      ->check(CLI::IsMember({"classes", "segments"}));
  app.add_option("--classes", args.classes,
                 "class map '<id> <name>' per line naming the labels (default: the file's "
                 "classes tag, else the taxonomy ids)");
  app.add_option("--view", args.view,
                 "auto (default: sensor for an organised camera frame, else oblique), top, "
                 "oblique or sensor (from the VIEWPOINT)")
      ->check(CLI::IsMember({"auto", "top", "oblique", "sensor"}));
  app.add_option("--width", args.width, "image width in pixels")->check(CLI::Range(64, 16384));
  app.add_option("--height", args.height, "image height in pixels")->check(CLI::Range(64, 16384));
  app.add_option("--point-size", args.point_size, "splat radius in pixels (0 = one pixel)")
      ->check(CLI::Range(0, 20));
  app.add_option("--title", args.title, "title (default: file name, field and point count)");
  app.add_flag("--no-title", args.no_title, "no title");
  app.add_flag("--no-legend", args.no_legend, "no legend");
  app.add_option("--primitives", args.primitives,
                 "draw the fitted primitives of this JSON file (primlabel label / primlabel-eval "
                 "--primitives): plane rectangles, cylinder and torus outlines with axes, sphere "
                 "circles, edge segments");
  app.add_option("--objects", args.objects,
                 "draw the table-top objects of this JSON file (primlabel label / primlabel-eval "
                 "--objects): the table's hull and each object's axis-aligned box");
  app.add_option("--min-confidence", args.min_confidence,
                 "with --primitives: leave out fits below this confidence")
      ->check(CLI::Range(0.0, 1.0));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "primlabel-render: usage error: %s (see --help)\n", e.what());
    return cli::kExitUsage;
  }
  try {
    return run(args);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "primlabel-render: usage error: %s\n", e.what());
    return cli::kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-render: error: %s\n", e.what());
    return cli::kExitFailure;
  }
}
