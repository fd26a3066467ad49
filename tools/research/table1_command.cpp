// primlabel-research table1: the paper's Table I re-measured on synthetic LMS400 scenes (CRF,
// node-only and SVM rows over FPFH and PFH; research/table1.hpp). Text, or one JSON line per row.
//
//   primlabel-research table1 --json
//   primlabel-research table1 --node-basis linear --no-pfh

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "node_basis.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/research/table1.hpp"
#include "research_commands.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  int train_scenes = 8, test_scenes = 4, pfh_max_neighbors = 40, threads = 0;
  bool no_pfh = false, no_svm = false, json = false, quiet = false;
  std::string node_basis = "tent";
  std::vector<float> node_knots;
};

int run_table1(const Arguments& args) {
  research::Table1Options options;
  // Bad knots are refused before any scene is described.
  try {
    options.node_knots = cli::node_knots(args.node_basis, args.node_knots);
  } catch (const std::invalid_argument& e) {
    throw research_tool::UsageError(e.what());
  }
  options.train_scenes = args.train_scenes;
  options.test_scenes = args.test_scenes;
  options.with_pfh = !args.no_pfh;
  options.with_svm = !args.no_svm;
  options.pfh_max_neighbors = args.pfh_max_neighbors;
  options.threads = args.threads;
  if (!args.quiet)
    options.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const auto rows = research::run_table1(options);
  std::fputs((args.json ? research::table1_json(rows) : research::table1_text(rows)).c_str(),
             stdout);
  return kExitOk;
}

}  // namespace

namespace primlabel::research_tool {

ResearchCommand add_table1_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd =
      parent.add_subcommand("table1", "Re-measure the paper's Table I on synthetic LMS400 scenes.");
  cmd->add_option("--train-scenes", args->train_scenes, "training scenes")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--test-scenes", args->test_scenes, "test scenes")->check(CLI::PositiveNumber);
  cmd->add_flag("--no-pfh", args->no_pfh, "FPFH rows only");
  cmd->add_flag("--no-svm", args->no_svm, "no SVM rows");
  cmd->add_option("--node-basis", args->node_basis,
                  "CRF / node-only node features, tent or linear (as the paper)")
      ->check(CLI::IsMember({"tent", "linear"}));
  cmd->add_option("--node-knots", args->node_knots, cli::kNodeKnotsHelp)->delimiter(',');
  cmd->add_option("--pfh-max-neighbors", args->pfh_max_neighbors,
                  "PFH uses the M nearest within the feature radius")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--json", args->json, "one JSON object per row on stdout");
  cmd->add_option("--threads", args->threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  cmd->add_flag("-q,--quiet", args->quiet, "no progress on stderr");
  return {cmd, [args] { return run_table1(*args); }};
}

}  // namespace primlabel::research_tool
