// primlabel-research: the paper's reproductions (Table I, Fig. 4) and the studies of real scenes
// (the mOSD report, the fitted object truth and its own error, the Kinect calibration), one
// subcommand each (docs/tools.md). This file only wires them: every subcommand binds its flags
// and runs in its own file (research_commands.hpp).

#include <CLI/CLI.hpp>
#include <string>

#include "primlabel/build_version.hpp"
#include "primlabel/cli/subcommands.hpp"
#include "research_commands.hpp"

int main(int argc, char** argv) {
  using namespace primlabel::research_tool;
  CLI::App app{
      "primlabel research: the paper's Table I and Fig. 4 re-measured, and the studies of "
      "real Kinect scenes (mOSD report, fitted object truth, sensor calibration)",
      "primlabel-research"};
  const std::string version = primlabel::version_line("primlabel-research");
  app.set_version_flag("--version", version);
  // Every option with a default shows it in --help ("[0.025]"); the subcommands inherit this.
  app.option_defaults()->always_capture_default();
  app.require_subcommand(1);
  // Each subcommand was a mode of primlabel-eval, which answered --version; they keep it.
  return primlabel::cli::run_subcommands(
      app,
      {add_table1_command(app), add_fig4_command(app), add_mosd_report_command(app),
       add_write_truth_command(app), add_truth_check_command(app),
       add_calibrate_kinect_command(app)},
      version, argc, argv);
}
