#pragma once
// The paper's reproductions and the studies of `primlabel-research`, one subcommand each. Every
// add_*_command is defined in its subcommand's own file: it binds the flags and returns how to
// run it, so research_main.cpp only wires them (the pattern of primlabel-bench).

#include "primlabel/cli/subcommands.hpp"

namespace primlabel::research_tool {

using ResearchCommand = cli::Subcommand;  // a study: its flags and how to run it

// A combination of flags the parser cannot check on its own: reported as bad usage (exit 2).
using cli::UsageError;

ResearchCommand add_table1_command(CLI::App& parent);            // table1_command.cpp
ResearchCommand add_fig4_command(CLI::App& parent);              // fig4_command.cpp
ResearchCommand add_mosd_report_command(CLI::App& parent);       // mosd_report_command.cpp
ResearchCommand add_write_truth_command(CLI::App& parent);       // write_truth_command.cpp
ResearchCommand add_truth_check_command(CLI::App& parent);       // truth_check_command.cpp
ResearchCommand add_calibrate_kinect_command(CLI::App& parent);  // calibrate_kinect_command.cpp

}  // namespace primlabel::research_tool
