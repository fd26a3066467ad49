// primlabel-research truth-check: the fitted object truth's own error. Fits and labels N held-out
// synthetic Kinect scenes (seeds 3000+) as it does real mOSD scenes and compares with their true
// labels, per class (research/truth_check.hpp).
//
//   primlabel-research truth-check 12 --json

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/research/truth_check.hpp"
#include "research_commands.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  int scenes = 0;
  double truth_radius = synth::ObjectTruthOptions{}.label_radius;
  bool json = false;
  int threads = 0;
};

int run_truth_check(const Arguments& args) {
  research::TruthCheckOptions options;
  options.scenes = args.scenes;
  options.truth.label_radius = args.truth_radius;
  const research::TruthCheck check =
      research::check_truth_on_synthetic(options, RunContext{args.threads, {}, {}});
  std::fputs(
      (args.json ? research::truth_check_json(check) : research::truth_check_text(check)).c_str(),
      stdout);
  return kExitOk;
}

}  // namespace

namespace primlabel::research_tool {

ResearchCommand add_truth_check_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "truth-check",
      "The fitted truth's own error: fit and label N held-out synthetic Kinect scenes and "
      "compare with their true labels, per class.");
  cmd->add_option("N", args->scenes, "held-out synthetic Kinect scenes (seeds 3000+)")
      ->required()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--truth-radius", args->truth_radius,
                  "label radius of the fitted truth (m), as primlabel-synth --radius")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--json", args->json, "the per-class scores as JSON on stdout");
  cmd->add_option("--threads", args->threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  return {cmd, [args] { return run_truth_check(*args); }};
}

}  // namespace primlabel::research_tool
