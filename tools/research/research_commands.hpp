#pragma once
// The paper's reproductions and the studies of `primlabel-research`, one subcommand each. Every
// add_*_command is defined in its subcommand's own file: it binds the flags and returns how to
// run it, so research_main.cpp only wires them (the pattern of primlabel-bench).

#include <functional>
#include <stdexcept>

namespace CLI {
class App;
}

namespace primlabel::research_tool {

struct ResearchCommand {
  CLI::App* command = nullptr;
  // Runs the subcommand with the parsed flags; returns the exit code (0 ok, 1 failure, 2 usage).
  std::function<int()> run;
};

// A combination of flags the parser cannot check on its own: reported as bad usage (exit 2).
struct UsageError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

ResearchCommand add_table1_command(CLI::App& parent);            // table1_command.cpp
ResearchCommand add_fig4_command(CLI::App& parent);              // fig4_command.cpp
ResearchCommand add_mosd_report_command(CLI::App& parent);       // mosd_report_command.cpp
ResearchCommand add_write_truth_command(CLI::App& parent);       // write_truth_command.cpp
ResearchCommand add_truth_check_command(CLI::App& parent);       // truth_check_command.cpp
ResearchCommand add_calibrate_kinect_command(CLI::App& parent);  // calibrate_kinect_command.cpp

}  // namespace primlabel::research_tool
