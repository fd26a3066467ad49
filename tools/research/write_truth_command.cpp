// primlabel-research write-truth: the fitted object truth of mOSD scenes alone (no model), as
// DIR/<scene>_truth.pcd per scene (taxonomy labels, 0 unscored, a `segment` field) and
// DIR/truth_fits.json; a line per scene on stdout. The real training data of tabletop-kinect
// (deploy/setup.sh kinect-model, bench/real_crossval.sh).
//
//   primlabel-research write-truth truth/ ../shared/data/mosd/learn*.pcd

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/research/mosd_report.hpp"
#include "research_commands.hpp"
#include "truth_outputs.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string dir;
  std::vector<std::string> scenes;
  double truth_radius = synth::ObjectTruthOptions{}.label_radius;
  int threads = 0;
};

int run_write_truth(const Arguments& args) {
  research_tool::make_directory(args.dir);
  json::Json scenes = json::Json::array();
  research::MosdObjectTruth all;
  for (const std::string& path : args.scenes) {
    const PointCloud cloud = read_cloud(path);
    research::MosdObjectTruth t;
    try {
      t = research::fit_mosd_truth(
          cloud, research_tool::truth_request(true, args.truth_radius, args.dir, path),
          RunContext{args.threads, {}, {}});
    } catch (const std::exception& e) {
      throw std::runtime_error(path + ": " + e.what());
    }
    std::printf(
        "%s: %zu segments: %zu box, %zu upright cylinder, %zu lying cylinder, %zu "
        "unfitted; %llu of %llu object points labeled; wrote %s\n",
        path.c_str(), t.objects.size(), t.count(synth::FittedKind::kBox),
        t.count(synth::FittedKind::kUprightCylinder),
        t.count(synth::FittedKind::kLyingCylinder), t.count(synth::FittedKind::kUnfitted),
        static_cast<unsigned long long>(t.truth_points),
        static_cast<unsigned long long>(t.object_points), t.truth_file.c_str());
    json::Json scene = research::object_truth_json(t, true);
    scene["file"] = path;
    scenes.push_back(std::move(scene));
    all.objects.insert(all.objects.end(), t.objects.begin(), t.objects.end());
    all.object_points += t.object_points;
    all.truth_points += t.truth_points;
  }
  const json::Json out = {{"scenes", std::move(scenes)},
                          {"overall", research::object_truth_json(all, false)}};
  atomic_write_file((std::filesystem::path(args.dir) / "truth_fits.json").string(),
                    json::dump(out) + "\n");
  return kExitOk;
}

}  // namespace

namespace primlabel::research_tool {

ResearchCommand add_write_truth_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "write-truth",
      "Write the fitted object truth of each mOSD scene as DIR/<scene>_truth.pcd (taxonomy "
      "labels, 0 unscored; a `segment` field), with DIR/truth_fits.json.");
  cmd->add_option("DIR", args->dir, "output folder")->required();
  cmd->add_option("SCENE", args->scenes, "mOSD scenes (.pcd with the label field)")->required();
  cmd->add_option("--truth-radius", args->truth_radius,
                  "label radius of the fitted truth (m), as primlabel-synth --radius")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--threads", args->threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  return {cmd, [args] { return run_write_truth(*args); }};
}

}  // namespace primlabel::research_tool
