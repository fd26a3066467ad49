// primlabel-research mosd-report: a model on real mOSD scenes (label 1-9 table, 20+ objects): the
// share of table points it labels plane, per scene and overall, a labeled PNG per scene and
// mosd_report.json in DIR (research/mosd_report.hpp). With --object-truth it also fits the object
// ground truth and scores the object points per class; --write-truth keeps that truth as files.
//
//   primlabel-research mosd-report out/ --model kinect.plm ../shared/data/mosd/*.pcd
//   primlabel-research mosd-report out/ --model kinect.plm --object-truth --write-truth t/ scenes

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/research/mosd_report.hpp"
#include "research_commands.hpp"
#include "truth_outputs.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string dir, model, truth_dir;
  std::vector<std::string> scenes;
  bool object_truth = false, tabletop_only = false, json = false, quiet = false;
  double truth_radius = synth::ObjectTruthOptions{}.label_radius;
  int threads = 0;
};

int run_mosd_report(const Arguments& args) {
  const LabelModel model = load_model(args.model);
  research_tool::make_directory(args.dir);
  if (!args.truth_dir.empty()) research_tool::make_directory(args.truth_dir);
  pipeline::LabelingOptions options;
  options.tabletop_only = args.tabletop_only;
  const RunContext context{args.threads, {}, {}};
  std::vector<research::MosdSceneReport> scenes;
  for (const std::string& path : args.scenes) {
    const std::string png = (std::filesystem::path(args.dir) /
                             (std::filesystem::path(path).stem().string() + "_labels.png"))
                                .string();
    const research::MosdTruthRequest truth =
        research_tool::truth_request(args.object_truth, args.truth_radius, args.truth_dir, path);
    scenes.push_back(research::report_mosd_scene(model, path, png, options, context, truth));
    if (!args.quiet)
      std::fprintf(stderr, "%s: %.2f%% of %llu table points plane, wrote %s\n", path.c_str(),
                   100.0 * scenes.back().plane_share(),
                   static_cast<unsigned long long>(scenes.back().table_points), png.c_str());
  }
  const research::MosdReport report = research::summarize_mosd(std::move(scenes));
  const std::string json = research::mosd_report_json(report);
  atomic_write_file((std::filesystem::path(args.dir) / "mosd_report.json").string(), json);
  std::fputs((args.json ? json : research::mosd_report_text(report)).c_str(), stdout);
  return kExitOk;
}

}  // namespace

namespace primlabel::research_tool {

ResearchCommand add_mosd_report_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "mosd-report",
      "A model on mOSD scenes (label 1-9 table): the share of table points labeled plane, and a "
      "labeled PNG per scene, into DIR (with mosd_report.json).");
  cmd->add_option("DIR", args->dir, "output folder")->required();
  cmd->add_option("SCENE", args->scenes, "mOSD scenes (.pcd with the label field)")->required();
  cmd->add_option("--model", args->model, "model file (primlabel-train -o)")->required();
  cmd->add_flag("--object-truth", args->object_truth,
                "also fit box / cylinder models to the object segments, label their points by the "
                "ground-truth rule and score the model on them per class");
  cmd->add_option("--write-truth", args->truth_dir,
                  "also write the fitted object truth of each scene into this folder as "
                  "<scene>_truth.pcd (taxonomy labels, 0 unscored; a `segment` field); implies "
                  "--object-truth");
  cmd->add_option("--truth-radius", args->truth_radius,
                  "label radius of the fitted truth (m), as primlabel-synth --radius")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--tabletop-only", args->tabletop_only,
                "label only the table and the objects on it");
  cmd->add_flag("--json", args->json, "the report as JSON (mosd_report.json) on stdout");
  cmd->add_option("--threads", args->threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  cmd->add_flag("-q,--quiet", args->quiet, "no progress on stderr");
  return {cmd, [args] { return run_mosd_report(*args); }};
}

}  // namespace primlabel::research_tool
