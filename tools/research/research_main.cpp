// primlabel-research: the paper's reproductions (Table I, Fig. 4) and the studies of real scenes
// (the mOSD report, the fitted object truth and its own error, the Kinect calibration), one
// subcommand each (docs/tools.md). This file only wires them: every subcommand binds its flags
// and runs in its own file (research_commands.hpp).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "primlabel/build_version.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "research_commands.hpp"

namespace {

// "primlabel-research table1" once the command line named a subcommand, so messages say which.
std::string command_name(const CLI::App& app) {
  const auto chosen = app.get_subcommands();
  return chosen.empty() ? app.get_name() : app.get_name() + " " + chosen.front()->get_name();
}

}  // namespace

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

  const std::vector<ResearchCommand> commands = {
      add_table1_command(app),      add_fig4_command(app),        add_mosd_report_command(app),
      add_write_truth_command(app), add_truth_check_command(app), add_calibrate_kinect_command(app),
  };
  // Each subcommand was a mode of primlabel-eval, which answered --version; they keep it.
  for (const ResearchCommand& command : commands)
    command.command->set_version_flag("--version", version);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);  // --help, --version
    std::fprintf(stderr, "%s: usage error: %s (see --help)\n", command_name(app).c_str(),
                 error.what());
    return primlabel::kExitUsage;
  }

  for (const ResearchCommand& command : commands) {
    if (!command.command->parsed()) continue;
    try {
      return command.run();
    } catch (const UsageError& error) {
      std::fprintf(stderr, "%s: usage error: %s\n", command_name(app).c_str(), error.what());
      return primlabel::kExitUsage;
    } catch (const std::exception& error) {
      std::fprintf(stderr, "%s: error: %s\n", command_name(app).c_str(), error.what());
      return primlabel::kExitFailure;
    }
  }
  return primlabel::kExitUsage;
}
